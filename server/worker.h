// The worker mode of vdbwrap-server (`vdbwrap-server --worker JOB_DIR`, started by the server
// for each job, never by hand): runs one job's wrap() or repair() in its own process, so that
// a crash, an exhausted memory limit or a hang ends that job only. It reads JOB_DIR/job.json
// and the input, writes the results and report.json into JOB_DIR (atomically), and reports
// progress and the verdict as frames on fd 3 (worker_protocol.h). SIGTERM cancels the job.
#pragma once
#include <string>

namespace vdbwrap::server {

// The worker's main(); returns the process exit code (0 once the verdict is sent, whatever it
// is; 1 when it could not be sent).
int run_worker(const std::string& job_dir);

}  // namespace vdbwrap::server
