// 64-bit FNV-1a of a byte string: identifies a study configuration in its
// results folder and a model file's compiled library in the model cache.
// Not cryptographic.
#ifndef ESTLAB_CORE_HASH_H_
#define ESTLAB_CORE_HASH_H_

#include <cstdint>
#include <cstdio>
#include <string>
#include <string_view>

namespace estlab {

// h = 14695981039346656037; for each byte c: h = (h xor c) * 1099511628211.
inline uint64_t Fnv1a64(std::string_view text, uint64_t h = 0xcbf29ce484222325ull) {
  for (unsigned char c : text) {
    h ^= c;
    h *= 0x100000001b3ull;
  }
  return h;
}

// The hash as 16 lowercase hex digits.
inline std::string HashHex(uint64_t h) {
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
  return buf;
}

}  // namespace estlab

#endif  // ESTLAB_CORE_HASH_H_
