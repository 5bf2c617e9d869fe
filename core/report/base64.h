// Base64 (RFC 4648) of raw bytes: the HTML report ships its arrays as typed-array bytes, about
// a third of the size of JSON number lists and parsed by the browser without a number parser.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace vdbwrap::report {

inline std::string base64(const void* data, size_t bytes) {
  static const char kAlphabet[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  const auto* in = static_cast<const uint8_t*>(data);
  std::string out;
  out.reserve((bytes + 2) / 3 * 4);
  size_t i = 0;
  for (; i + 2 < bytes; i += 3) {
    const uint32_t v = (uint32_t(in[i]) << 16) | (uint32_t(in[i + 1]) << 8) | in[i + 2];
    out += kAlphabet[v >> 18], out += kAlphabet[(v >> 12) & 63], out += kAlphabet[(v >> 6) & 63],
        out += kAlphabet[v & 63];
  }
  if (i < bytes) {
    uint32_t v = uint32_t(in[i]) << 16;
    if (i + 1 < bytes) v |= uint32_t(in[i + 1]) << 8;
    out += kAlphabet[v >> 18], out += kAlphabet[(v >> 12) & 63];
    out += i + 1 < bytes ? kAlphabet[(v >> 6) & 63] : '=';
    out += '=';
  }
  return out;
}

// Typed arrays are read in the browser's byte order, which is little-endian on every platform
// browsers run on; so is every platform vdbwrap builds for.
template <typename T>
std::string base64(const std::vector<T>& values) {
  return base64(values.data(), values.size() * sizeof(T));
}

}  // namespace vdbwrap::report
