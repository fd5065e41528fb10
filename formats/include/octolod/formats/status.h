// Status and Result<T>: how every octolod function reports an expected failure (bad input,
// unsupported feature, I/O error) without throwing. Programmer misuse is an assert instead.
#pragma once

#include <cassert>
#include <optional>
#include <string>
#include <utility>

namespace octolod {

// Failure classes. The numeric values are the CLI's exit codes.
enum class ErrorCode : int {
  ok = 0,
  usage = 1,        // the caller asked for something meaningless (bad option)
  bad_input = 2,    // malformed or inconsistent input data
  unsupported = 3,  // valid input using a feature octolod does not handle
  io = 4,           // the operating system refused: open, read, write, rename, out of space
};

class [[nodiscard]] Status {
 public:
  Status() = default;
  Status(ErrorCode code, std::string message) : code_(code), message_(std::move(message)) {}

  bool ok() const { return code_ == ErrorCode::ok; }
  ErrorCode code() const { return code_; }
  // Human-readable, names the file and the line or byte offset where that applies.
  const std::string& message() const { return message_; }

 private:
  ErrorCode code_ = ErrorCode::ok;
  std::string message_;
};

inline Status bad_input_error(std::string message) { return {ErrorCode::bad_input, std::move(message)}; }
inline Status unsupported_error(std::string message) { return {ErrorCode::unsupported, std::move(message)}; }
inline Status io_error(std::string message) { return {ErrorCode::io, std::move(message)}; }
inline Status usage_error(std::string message) { return {ErrorCode::usage, std::move(message)}; }

// A value or the Status that explains why there is none.
template <class T>
class [[nodiscard]] Result {
 public:
  Result(T value) : value_(std::move(value)) {}  // NOLINT: implicit by design
  Result(Status status) : status_(std::move(status)) {  // NOLINT: implicit by design
    assert(!status_.ok() && "Result<T> built from an ok Status: return the value instead");
  }

  bool ok() const { return value_.has_value(); }
  const Status& status() const { return status_; }
  T& value() & {
    assert(ok() && "Result::value() on an error: check ok() first");
    return *value_;
  }
  const T& value() const& {
    assert(ok() && "Result::value() on an error: check ok() first");
    return *value_;
  }
  T&& value() && {
    assert(ok() && "Result::value() on an error: check ok() first");
    return std::move(*value_);
  }
  T* operator->() { return &value(); }
  const T* operator->() const { return &value(); }

 private:
  std::optional<T> value_;
  Status status_;
};

// The message of a nlohmann::json exception (its what()) without the library's
// "[json.exception.parse_error.101] " tag: what the errors that quote it show a user.
inline std::string without_json_tag(const std::string& what) {
  const std::size_t tag_end = what.find("] ");
  return tag_end == std::string::npos ? what : what.substr(tag_end + 2);
}

}  // namespace octolod

// Propagates a failed Status out of the enclosing function.
#define OCTOLOD_RETURN_IF_ERROR(expr)          \
  do {                                         \
    ::octolod::Status octolod_status_ = (expr); \
    if (!octolod_status_.ok()) return octolod_status_; \
  } while (false)
