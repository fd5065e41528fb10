// PLY body syntax: reading the values of one element after another, in ascii or in binary of
// either byte order, from a bounded FileBuffer. Both sources offer the same operations so the
// element decoders in ply_reader.cpp are written once (as templates) for all three formats.
//
// Element entries are counted from 0 in messages ("vertex 5 of 10" is the sixth vertex).
// ASCII rule: every element entry sits on one line of its own (blank lines between entries are
// allowed); too few values on a line, or extra values after an entry, are errors naming the line.
#pragma once

#include <cerrno>
#include <charconv>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <string>
#include <string_view>
#include <type_traits>

#include "octolod/formats/status.h"
#include "ply_file_buffer.h"
#include "ply_header.h"

namespace octolod::ply {

// Which element entry is being read, for messages.
struct EntryContext {
  const std::string* element = nullptr;
  std::uint64_t index = 0;
  std::uint64_t count = 0;

  std::string describe() const {
    if (element == nullptr) return "the body";
    return *element + " " + std::to_string(index) + " of " + std::to_string(count);
  }
};

template <bool kSwap>
class BinarySource {
 public:
  static constexpr bool kBinary = true;
  static constexpr bool kSwapBytes = kSwap;

  explicit BinarySource(FileBuffer& in) : in_(in) {}
  FileBuffer& in() { return in_; }

  // Where the next value starts (a byte offset), cheap to take before every value.
  std::uint64_t position() const { return in_.offset(); }
  std::string message_at(std::uint64_t position, std::string_view what) const {
    return message_at_offset(in_.path(), position, what);
  }
  std::string message(std::string_view what) const { return message_at(position(), what); }

  Status begin_entry(const EntryContext& context) {
    context_ = context;
    return {};
  }
  Status end_entry() { return {}; }

  // Integer and float values alike, exactly (every PLY type fits a double).
  Status read_number(ScalarType type, double& out) {
    OCTOLOD_RETURN_IF_ERROR(need(size_of(type)));
    out = load_as_double<kSwap>(in_.data(), type);
    in_.consume(size_of(type));
    return {};
  }
  // `type` must be an integer type (list counts and vertex indices).
  Status read_integer(ScalarType type, std::int64_t& out) {
    OCTOLOD_RETURN_IF_ERROR(need(size_of(type)));
    out = load_as_int<kSwap>(in_.data(), type);
    in_.consume(size_of(type));
    return {};
  }
  Status skip_values(ScalarType type, std::uint64_t count) {
    const std::uint64_t start = in_.offset();
    // No overflow: list counts have at most 32 bits and items at most 8 bytes.
    const std::uint64_t bytes = count * size_of(type);
    OCTOLOD_RETURN_IF_ERROR(in_.skip(bytes));
    if (in_.offset() > in_.file_size())
      return bad_input_error(message_at_offset(
          in_.path(), start,
          "file truncated in " + context_.describe() + ": " + std::to_string(bytes) +
              " bytes of list items, " + std::to_string(in_.file_size() - start) + " left"));
    return {};
  }
  // Skips `count` whole entries of `bytes_each` bytes (an element without lists).
  Status skip_entries(std::uint64_t count, std::uint64_t bytes_each, const EntryContext& context) {
    const std::uint64_t start = in_.offset();
    OCTOLOD_RETURN_IF_ERROR(in_.skip(count * bytes_each));
    if (in_.offset() > in_.file_size())
      return bad_input_error(message_at_offset(
          in_.path(), start + (in_.file_size() - start) / bytes_each * bytes_each,
          "file truncated in " + *context.element + " " +
              std::to_string(context.index + (in_.file_size() - start) / bytes_each) + " of " +
              std::to_string(context.count)));
    return {};
  }

  // Makes `n` bytes available or reports truncation.
  Status need(std::size_t n) {
    if (in_.available() >= n) return {};
    OCTOLOD_RETURN_IF_ERROR(in_.fill(n));
    if (in_.available() >= n) return {};
    return bad_input_error(message(
        "file truncated in " + context_.describe() + ": needs " + std::to_string(n) +
        " more bytes, " + std::to_string(in_.available()) + " left"));
  }

  // Binary bodies may be followed by anything (some writers pad): trailing bytes are ignored.
  Status check_trailing() { return {}; }

 private:
  FileBuffer& in_;
  EntryContext context_;
};

class AsciiSource {
 public:
  static constexpr bool kBinary = false;
  static constexpr std::size_t kMaxToken = 1024;

  AsciiSource(FileBuffer& in, std::uint64_t first_line) : in_(in), line_(first_line) {}
  FileBuffer& in() { return in_; }

  // Where the current entry is (its line), cheap to take before every value.
  std::uint64_t position() const { return entry_line_; }
  std::string message_at(std::uint64_t position, std::string_view what) const {
    return message_at_line(in_.path(), position, what);
  }
  std::string message(std::string_view what) const { return message_at(position(), what); }

  Status begin_entry(const EntryContext& context) {
    context_ = context;
    bool more = false;
    OCTOLOD_RETURN_IF_ERROR(skip_space(true, more));
    entry_line_ = line_;
    if (!more)
      return bad_input_error(message(
          "file ends early: element '" + *context.element + "' declares " +
          std::to_string(context.count) + " entries, found " + std::to_string(context.index)));
    return {};
  }

  // The entry must end its line.
  Status end_entry() {
    bool more = false;
    OCTOLOD_RETURN_IF_ERROR(skip_space(false, more));
    if (more && in_.data()[0] != '\n') {
      std::string_view token;
      OCTOLOD_RETURN_IF_ERROR(scan_token(token));
      return bad_input_error(message("extra value '" + std::string(token) + "' after " +
                                     context_.describe()));
    }
    return {};
  }

  Status read_number(ScalarType type, double& out) {
    std::string_view token;
    OCTOLOD_RETURN_IF_ERROR(next_token(token));
    bool ok = false;
    if (is_integer(type)) {
      std::int64_t value = 0;
      ok = parse_integer(token, type, value);
      out = static_cast<double>(value);
    } else if (type == ScalarType::float32) {
      float value = 0;
      ok = parse_real(token, value);
      out = value;
    } else {
      ok = parse_real(token, out);
    }
    if (!ok) return bad_value(token, type);
    in_.consume(token.size());
    return {};
  }

  Status read_integer(ScalarType type, std::int64_t& out) {
    std::string_view token;
    OCTOLOD_RETURN_IF_ERROR(next_token(token));
    if (!parse_integer(token, type, out)) return bad_value(token, type);
    in_.consume(token.size());
    return {};
  }

  Status skip_values(ScalarType, std::uint64_t count) {
    for (std::uint64_t i = 0; i < count; ++i) {
      std::string_view token;
      OCTOLOD_RETURN_IF_ERROR(next_token(token));
      in_.consume(token.size());
    }
    return {};
  }

  // Only whitespace may follow the last element.
  Status check_trailing() {
    bool more = false;
    OCTOLOD_RETURN_IF_ERROR(skip_space(true, more));
    if (!more) return {};
    entry_line_ = line_;
    std::string_view token;
    OCTOLOD_RETURN_IF_ERROR(scan_token(token));
    return bad_input_error(
        message("unexpected data '" + std::string(token) + "' after the last element"));
  }

 private:
  static bool is_space(char c) {
    return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\v' || c == '\f';
  }

  // Skips whitespace (newlines too when `cross_lines`, counting them); `more` tells whether a
  // byte follows (with !cross_lines it may be the '\n').
  Status skip_space(bool cross_lines, bool& more) {
    for (;;) {
      OCTOLOD_RETURN_IF_ERROR(in_.fill(1));
      const char* data = in_.data();
      const std::size_t n = in_.available();
      if (n == 0) {
        more = false;
        return {};
      }
      std::size_t i = 0;
      for (; i < n && is_space(data[i]); ++i) {
        if (data[i] == '\n') {
          if (!cross_lines) break;
          ++line_;
        }
      }
      in_.consume(i);
      if (i < n) {
        more = true;
        return {};
      }
    }
  }

  // The token at the read position (not consumed). Precondition: a non-space byte is there.
  Status scan_token(std::string_view& token) {
    std::size_t n = 0;
    for (;;) {
      const char* data = in_.data();
      const std::size_t available = in_.available();
      while (n < available && !is_space(data[n])) ++n;
      if (n < available || in_.exhausted()) break;
      if (n >= kMaxToken)
        return bad_input_error(message("value longer than " + std::to_string(kMaxToken) +
                                       " characters in " + context_.describe()));
      OCTOLOD_RETURN_IF_ERROR(in_.fill(available + 1));
    }
    if (n > kMaxToken)
      return bad_input_error(message("value longer than " + std::to_string(kMaxToken) +
                                     " characters in " + context_.describe()));
    token = std::string_view(in_.data(), n);
    return {};
  }

  // The next value of the current entry, which must be on the entry's line.
  Status next_token(std::string_view& token) {
    bool more = false;
    OCTOLOD_RETURN_IF_ERROR(skip_space(true, more));
    if (!more || line_ != entry_line_)
      return bad_input_error(message(context_.describe() + " has too few values" +
                                     (more ? "" : " (the file ends)")));
    return scan_token(token);
  }

  static std::string_view without_plus(std::string_view token) {
    if (token.size() > 1 && token[0] == '+' && token[1] != '-') token.remove_prefix(1);
    return token;
  }

  static bool parse_integer(std::string_view token, ScalarType type, std::int64_t& out) {
    token = without_plus(token);
    const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), out);
    if (ec != std::errc() || end != token.data() + token.size()) return false;
    const double lowest = type == ScalarType::int8    ? -128.0
                          : type == ScalarType::int16 ? -32768.0
                          : type == ScalarType::int32 ? -2147483648.0
                                                      : 0.0;
    return static_cast<double>(out) >= lowest && static_cast<double>(out) <= max_value(type);
  }

  // Shortest round-trip text parses back bit-exactly, so float32 values are parsed as float.
  // Values beyond the type's range parse as +-inf (and underflow as 0), like strtod.
  template <class Real>
  static bool parse_real(std::string_view token, Real& out) {
    token = without_plus(token);
    const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), out);
    if (end != token.data() + token.size()) return false;
    if (ec == std::errc()) return true;
    if (ec != std::errc::result_out_of_range) return false;
    const std::string copy(token);  // rare: strtod needs a terminated string
    if constexpr (std::is_same_v<Real, float>) {
      out = std::strtof(copy.c_str(), nullptr);
    } else {
      out = std::strtod(copy.c_str(), nullptr);
    }
    return true;
  }

  Status bad_value(std::string_view token, ScalarType type) const {
    return bad_input_error(message("bad " + std::string(to_string(type)) + " value '" +
                                   std::string(token.substr(0, 40)) + "' in " +
                                   context_.describe()));
  }

  FileBuffer& in_;
  std::uint64_t line_ = 1;        // line of the read position
  std::uint64_t entry_line_ = 1;  // line of the current entry
  EntryContext context_;
};

}  // namespace octolod::ply
