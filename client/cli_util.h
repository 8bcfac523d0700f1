#pragma once

#include <map>
#include <string>

#include "absl/status/status.h"
#include "absl/status/statusor.h"

namespace fenestra {

// Prints "error: <message>" to stderr and ends the command with exit code 1.
[[noreturn]] void Fail(const absl::Status& status);

// Returns the value, or Fail()s with its status.
template <typename T>
T ValueOrFail(absl::StatusOr<T> value) {
  if (!value.ok()) Fail(value.status());
  return *std::move(value);
}

// Parses "alpha=0.5,width=0.12" into name -> value.
absl::StatusOr<std::map<std::string, double>> ParseDesignValues(const std::string& text);

}  // namespace fenestra
