#pragma once

#include <string>
#include <string_view>

namespace fenestra {

// SHA-256 of `data` (FIPS 180-4, through OpenSSL): 32 raw bytes.
std::string Sha256(std::string_view data);

// SHA-256 of `data` as 64 lowercase hex digits.
std::string Sha256Hex(std::string_view data);

}  // namespace fenestra
