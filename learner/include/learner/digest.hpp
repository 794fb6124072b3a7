#pragma once
// FNV-1a over bytes: the digests that say two processes hold the same data (data sets,
// MDPs) and the numerics fingerprint. Not a defence against forgery, only against
// mix-ups; the data behind a digest is always validated itself.
#include <cstddef>
#include <cstdint>

namespace hbirl {

class Fnv1a {
 public:
  void add(const void* data, size_t size) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (size_t i = 0; i < size; ++i) hash_ = (hash_ ^ p[i]) * 0x100000001b3ULL;
  }
  template <class T>
  void add(const T& value) {
    add(&value, sizeof value);
  }
  std::uint64_t value() const { return hash_; }

 private:
  std::uint64_t hash_ = 0xcbf29ce484222325ULL;
};

}  // namespace hbirl
