// The CLI's remote mode: `vdbwrap submit`, `wait`, `jobs`, `cancel`, `delete`, `health` talk to a vdbwrap-server
// (gRPC, vdbwrap.v1.Jobs). Thin: options -> API messages (through the one mapping of
// proto/params_mapping.h), progress display, downloads, exit codes like `vdbwrap wrap`.
#pragma once
#include <CLI/CLI.hpp>

#include <memory>
#include <optional>

namespace vdbwrap::remote {

class RemoteCommands {
 public:
  // Adds the subcommands to app (before app.parse()).
  explicit RemoteCommands(CLI::App& app);
  ~RemoteCommands();
  // After app.parse(): when a remote subcommand was given, runs it and returns its exit code.
  std::optional<int> run();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace vdbwrap::remote
