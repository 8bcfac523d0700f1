#pragma once

#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>
#include <type_traits>

namespace fenestra {

// A stable 128-bit content hash (two FNV-1a 64-bit lanes with different offsets) of the
// bytes fed to it, the same on every run and platform of one endianness. For cache keys,
// not for security.
class ContentHash {
 public:
  void Bytes(const void* data, size_t size) {
    const auto* bytes = static_cast<const unsigned char*>(data);
    for (size_t i = 0; i < size; ++i) {
      a_ = (a_ ^ bytes[i]) * kPrime;
      b_ = (b_ ^ bytes[i]) * kPrime;
      b_ ^= b_ >> 29;
    }
  }
  template <typename T>
  void Value(const T& value) {
    static_assert(std::is_arithmetic_v<T>);
    Bytes(&value, sizeof value);
  }
  void String(std::string_view s) {
    Value(static_cast<uint64_t>(s.size()));
    Bytes(s.data(), s.size());
  }
  // 32 hexadecimal digits.
  std::string Hex() const {
    static constexpr char kDigits[] = "0123456789abcdef";
    std::string out(32, '0');
    for (int i = 0; i < 16; ++i) {
      out[15 - i] = kDigits[(a_ >> (4 * i)) & 15];
      out[31 - i] = kDigits[(b_ >> (4 * i)) & 15];
    }
    return out;
  }

 private:
  static constexpr uint64_t kPrime = 0x100000001b3ull;
  uint64_t a_ = 0xcbf29ce484222325ull;
  uint64_t b_ = 0x84222325cbf29ce4ull;
};

}  // namespace fenestra
