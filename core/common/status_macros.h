#pragma once

#include "absl/status/status.h"

// Evaluates an absl::StatusOr<T> expression; returns its status on error, otherwise
// declares `lhs` holding the value.
#define FENESTRA_ASSIGN_OR_RETURN(lhs, expr)      \
  auto lhs##_or_ = (expr);                        \
  if (!lhs##_or_.ok()) return lhs##_or_.status(); \
  auto lhs = *std::move(lhs##_or_)

// Returns the status of an absl::Status expression when it is an error.
#define FENESTRA_RETURN_IF_ERROR(expr)                   \
  do {                                                   \
    absl::Status fenestra_status_ = (expr);              \
    if (!fenestra_status_.ok()) return fenestra_status_; \
  } while (false)
