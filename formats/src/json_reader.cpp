// read_json, see json_reader.h.
#include "json_reader.h"

#include <algorithm>
#include <charconv>
#include <system_error>
#include <vector>

namespace octolod {
namespace {

using Sax = nlohmann::json_sax<nlohmann::json>;

constexpr int kEnd = -1;
constexpr std::size_t kUnknownSize = static_cast<std::size_t>(-1);  // nlohmann's elements argument

std::string describe(int c) {
  if (c == kEnd) return "the end of the text";
  if (c == '\n') return "a line break";
  if (c >= 0x20 && c < 0x7F) return std::string("'") + static_cast<char>(c) + "'";
  static constexpr char kHex[] = "0123456789ABCDEF";
  return std::string("byte 0x") + kHex[c >> 4] + kHex[c & 15];
}

void append_utf8(std::uint32_t code, std::string& out) {
  if (code < 0x80) {
    out += static_cast<char>(code);
  } else if (code < 0x800) {
    out += static_cast<char>(0xC0 | (code >> 6));
    out += static_cast<char>(0x80 | (code & 0x3F));
  } else if (code < 0x10000) {
    out += static_cast<char>(0xE0 | (code >> 12));
    out += static_cast<char>(0x80 | ((code >> 6) & 0x3F));
    out += static_cast<char>(0x80 | (code & 0x3F));
  } else {
    out += static_cast<char>(0xF0 | (code >> 18));
    out += static_cast<char>(0x80 | ((code >> 12) & 0x3F));
    out += static_cast<char>(0x80 | ((code >> 6) & 0x3F));
    out += static_cast<char>(0x80 | (code & 0x3F));
  }
}

// Whether a number whose conversion is out of range is too large (else it is too small): its
// decimal exponent, from the position of its first non-zero digit and its exponent part, is
// positive. (An all-zero mantissa is never out of range.)
bool overflows(std::string_view number) {
  std::size_t i = number[0] == '-' ? 1 : 0;
  long long exponent = 0;  // of the first non-zero digit, plus one
  bool point = false, nonzero = false;
  for (; i < number.size() && number[i] != 'e' && number[i] != 'E'; ++i) {
    if (number[i] == '.') {
      point = true;
    } else if (!nonzero && number[i] == '0') {
      if (point) --exponent;
    } else {
      nonzero = true;
      if (!point) ++exponent;
    }
  }
  if (i < number.size()) {  // the exponent part, saturated
    ++i;
    const bool negative = number[i] == '-';
    if (number[i] == '-' || number[i] == '+') ++i;
    long long e = 0;
    for (; i < number.size(); ++i) e = std::min<long long>(e * 10 + (number[i] - '0'), 1LL << 40);
    exponent += negative ? -e : e;
  }
  return exponent > 0;
}

class Reader {
 public:
  explicit Reader(std::string_view text) : start_(text.data()), p_(text.data()), end_(text.data() + text.size()) {}
  Reader(std::istream& in, std::size_t chunk_bytes) : in_(&in), buffer_(chunk_bytes) {}

  JsonReadResult run(Sax& sax);

 private:
  enum class State { value, key, after_value };

  bool refill() {
    if (!in_) return false;
    consumed_ += static_cast<std::uint64_t>(end_ - start_);
    in_->read(buffer_.data(), static_cast<std::streamsize>(buffer_.size()));
    const auto got = static_cast<std::size_t>(in_->gcount());
    start_ = p_ = buffer_.data();
    end_ = start_ + got;
    return got > 0;
  }
  int peek() { return p_ != end_ || refill() ? static_cast<unsigned char>(*p_) : kEnd; }
  int next() {
    const int c = peek();
    if (c != kEnd) ++p_;
    return c;
  }
  // (line breaks can only be whitespace: inside strings they are errors)
  void skip_whitespace() {
    for (int c = peek(); c == ' ' || c == '\t' || c == '\n' || c == '\r'; c = peek()) {
      ++p_;
      if (c == '\n') ++line_, line_start_ = offset();
    }
  }
  std::uint64_t offset() const { return consumed_ + static_cast<std::uint64_t>(p_ - start_); }
  bool fail(const std::string& what) {
    if (error_.empty())
      error_ = "syntax error at line " + std::to_string(line_) + ", column " +
               std::to_string(offset() - line_start_ + 1) + " (byte " + std::to_string(offset()) + "): " + what;
    return false;
  }

  bool read_string(std::string& out);
  bool read_escape(std::string& out);
  bool read_utf8(int lead, std::string& out);
  bool read_hex4(std::uint32_t& code);
  bool read_number(Sax& sax, bool& handled);
  bool read_literal(std::string_view word);

  std::istream* in_ = nullptr;
  std::vector<char> buffer_;
  const char* start_ = nullptr;  // the bytes at hand, from offset consumed_ of the text
  const char* p_ = nullptr;
  const char* end_ = nullptr;
  std::uint64_t consumed_ = 0;
  std::uint64_t line_ = 1, line_start_ = 0;  // the line being read, and the offset it starts at
  std::string token_;
  std::string error_;
};

bool Reader::read_hex4(std::uint32_t& code) {
  code = 0;
  for (int k = 0; k < 4; ++k, ++p_) {
    const int c = peek();
    int digit;
    if (c >= '0' && c <= '9') digit = c - '0';
    else if (c >= 'a' && c <= 'f') digit = c - 'a' + 10;
    else if (c >= 'A' && c <= 'F') digit = c - 'A' + 10;
    else return fail("expected a hexadecimal digit in a \\u escape, found " + describe(c));
    code = code * 16 + static_cast<std::uint32_t>(digit);
  }
  return true;
}

bool Reader::read_escape(std::string& out) {
  const int c = peek();
  if (c != kEnd) ++p_;
  switch (c) {
    case '"': out += '"'; return true;
    case '\\': out += '\\'; return true;
    case '/': out += '/'; return true;
    case 'b': out += '\b'; return true;
    case 'f': out += '\f'; return true;
    case 'n': out += '\n'; return true;
    case 'r': out += '\r'; return true;
    case 't': out += '\t'; return true;
    case 'u': break;
    case kEnd: return fail("the text ends inside a string");
    default: --p_; return fail("invalid escape: a backslash before " + describe(c) + " in a string");
  }
  std::uint32_t code;
  if (!read_hex4(code)) return false;
  if (code >= 0xDC00 && code <= 0xDFFF) return fail("a \\u escape of a low surrogate without a high one before it");
  if (code >= 0xD800 && code <= 0xDBFF) {
    std::uint32_t low;
    if (peek() != '\\' || (++p_, peek() != 'u'))
      return fail("a \\u escape of a high surrogate without a low one after it");
    ++p_;
    if (!read_hex4(low)) return false;
    if (low < 0xDC00 || low > 0xDFFF) return fail("a \\u escape of a high surrogate without a low one after it");
    code = 0x10000 + ((code - 0xD800) << 10) + (low - 0xDC00);
  }
  append_utf8(code, out);
  return true;
}

// One UTF-8 sequence after its lead byte (>= 0x80), in the ranges of RFC 3629.
bool Reader::read_utf8(int lead, std::string& out) {
  int count;                  // continuation bytes
  int low = 0x80, high = 0xBF;  // the first continuation byte's range
  if (lead >= 0xC2 && lead <= 0xDF) count = 1;
  else if (lead == 0xE0) count = 2, low = 0xA0;
  else if (lead >= 0xE1 && lead <= 0xEC) count = 2;
  else if (lead == 0xED) count = 2, high = 0x9F;
  else if (lead >= 0xEE && lead <= 0xEF) count = 2;
  else if (lead == 0xF0) count = 3, low = 0x90;
  else if (lead >= 0xF1 && lead <= 0xF3) count = 3;
  else if (lead == 0xF4) count = 3, high = 0x8F;
  else return fail("invalid UTF-8 in a string (" + describe(lead) + ")");
  out += static_cast<char>(lead);
  for (int k = 0; k < count; ++k, ++p_) {
    const int c = peek();
    if (c == kEnd || c < low || c > high) return fail("invalid UTF-8 in a string (" + describe(c) + ")");
    out += static_cast<char>(c);
    low = 0x80, high = 0xBF;
  }
  return true;
}

bool Reader::read_string(std::string& out) {
  out.clear();
  ++p_;  // the opening quote, seen by the caller
  for (;;) {
    // a run of plain characters at once
    const char* run = p_;
    while (p_ != end_) {
      const auto c = static_cast<unsigned char>(*p_);
      if (c == '"' || c == '\\' || c < 0x20 || c >= 0x80) break;
      ++p_;
    }
    out.append(run, static_cast<std::size_t>(p_ - run));
    const int c = peek();
    if (c == kEnd) return fail("the text ends inside a string");
    if (c == '"') {
      ++p_;
      return true;
    }
    if (c == '\\') {
      ++p_;
      if (!read_escape(out)) return false;
    } else if (c < 0x20) {
      return fail("a control character (" + describe(c) + ") in a string must be escaped");
    } else if (c >= 0x80) {
      ++p_;
      if (!read_utf8(c, out)) return false;
    }
  }
}

// A number as nlohmann's lexer reads it: -?(0|[1-9][0-9]*)(.[0-9]+)?([eE][+-]?[0-9]+)?. `handled`
// is what the handler returned.
bool Reader::read_number(Sax& sax, bool& handled) {
  token_.clear();
  // the digits from here on, a run at a time (across refills)
  auto digits = [&](bool at_least_one) {
    if (at_least_one && !(peek() >= '0' && peek() <= '9'))
      return fail("expected a digit in a number, found " + describe(peek()));
    do {
      const char* run = p_;
      while (p_ != end_ && *p_ >= '0' && *p_ <= '9') ++p_;
      token_.append(run, static_cast<std::size_t>(p_ - run));
    } while (p_ == end_ && refill());
    return true;
  };
  if (peek() == '-') token_ += static_cast<char>(next());
  if (peek() == '0') token_ += static_cast<char>(next());
  else if (!digits(true)) return false;
  bool integer = true;
  if (peek() == '.') {
    integer = false;
    token_ += static_cast<char>(next());
    if (!digits(true)) return false;
  }
  if (peek() == 'e' || peek() == 'E') {
    integer = false;
    token_ += static_cast<char>(next());
    if (peek() == '+' || peek() == '-') token_ += static_cast<char>(next());
    if (!digits(true)) return false;
  }
  const char* first = token_.data();
  const char* last = token_.data() + token_.size();
  if (integer) {  // beyond 64 bits: a float, as nlohmann has it
    if (token_[0] == '-') {
      std::int64_t value;
      if (std::from_chars(first, last, value).ec == std::errc{}) {
        handled = sax.number_integer(value);
        return true;
      }
    } else {
      std::uint64_t value;
      if (std::from_chars(first, last, value).ec == std::errc{}) {
        handled = sax.number_unsigned(value);
        return true;
      }
    }
  }
  double value = 0.0;
  const std::from_chars_result converted = std::from_chars(first, last, value);
  if (converted.ec == std::errc::result_out_of_range) {
    if (overflows(token_)) return fail("number overflow: " + token_ + " is beyond the range of a double");
    value = token_[0] == '-' ? -0.0 : 0.0;  // below the smallest double: 0, as strtod rounds it
  } else if (converted.ec != std::errc{} || converted.ptr != last) {
    return fail("cannot convert the number " + token_);
  }
  handled = sax.number_float(value, token_);
  return true;
}

bool Reader::read_literal(std::string_view word) {
  for (const char expected : word) {
    const int c = peek();
    if (c != static_cast<unsigned char>(expected))
      return fail("invalid literal: expected \"" + std::string(word) + "\", found " + describe(c));
    ++p_;
  }
  return true;
}

JsonReadResult Reader::run(Sax& sax) {
  JsonReadResult result;
  auto stop = [&] {
    result.stopped = true;
    return result;
  };
  auto failed = [&] {
    result.error = error_;
    return result;
  };
  auto syntax_error = [&](const std::string& what) {
    fail(what);
    return failed();
  };
  if (peek() == 0xEF) {  // a byte order mark
    ++p_;
    if (next() != 0xBB || next() != 0xBF) return syntax_error("an invalid byte order mark (UTF-8's is EF BB BF)");
  }
  std::vector<char> open;  // '{' or '[' per container open
  State state = State::value;
  for (;;) {
    skip_whitespace();
    const int c = peek();
    switch (state) {
      case State::value:
        switch (c) {
          case '{':
          case '[': {  // an empty container closes at once
            const bool object = c == '{';
            ++p_;
            if (!(object ? sax.start_object(kUnknownSize) : sax.start_array(kUnknownSize))) return stop();
            skip_whitespace();
            if (peek() == (object ? '}' : ']')) {
              ++p_;
              if (!(object ? sax.end_object() : sax.end_array())) return stop();
              state = State::after_value;
            } else {
              open.push_back(static_cast<char>(c));
              state = object ? State::key : State::value;
            }
            continue;
          }
          case '"':
            if (!read_string(token_)) return failed();
            if (!sax.string(token_)) return stop();
            break;
          case 't':
            if (!read_literal("true")) return failed();
            if (!sax.boolean(true)) return stop();
            break;
          case 'f':
            if (!read_literal("false")) return failed();
            if (!sax.boolean(false)) return stop();
            break;
          case 'n':
            if (!read_literal("null")) return failed();
            if (!sax.null()) return stop();
            break;
          default:
            if (c == '-' || (c >= '0' && c <= '9')) {
              bool handled = true;
              if (!read_number(sax, handled)) return failed();
              if (!handled) return stop();
              break;
            }
            return syntax_error("expected a value, found " + describe(c));
        }
        state = State::after_value;
        continue;
      case State::key:
        if (c != '"') return syntax_error("expected a string as an object key, found " + describe(c));
        if (!read_string(token_)) return failed();
        if (!sax.key(token_)) return stop();
        skip_whitespace();
        if (peek() != ':') return syntax_error("expected ':' after an object key, found " + describe(peek()));
        ++p_;
        state = State::value;
        continue;
      case State::after_value:
        if (open.empty()) {
          if (c != kEnd) return syntax_error("expected the end of the text after the value, found " + describe(c));
          return result;
        }
        if (c == ',') {
          ++p_;
          state = open.back() == '{' ? State::key : State::value;
          continue;
        }
        if (open.back() == '{' && c == '}') {
          ++p_;
          open.pop_back();
          if (!sax.end_object()) return stop();
          continue;
        }
        if (open.back() == '[' && c == ']') {
          ++p_;
          open.pop_back();
          if (!sax.end_array()) return stop();
          continue;
        }
        return syntax_error(std::string(open.back() == '{' ? "expected ',' or '}' after an object member, found "
                                                           : "expected ',' or ']' after an array element, found ") +
                            describe(c));
    }
  }
}

}  // namespace

JsonReadResult read_json(std::string_view text, Sax& sax) { return Reader(text).run(sax); }

JsonReadResult read_json(std::istream& in, Sax& sax, std::size_t chunk_bytes) {
  return Reader(in, chunk_bytes == 0 ? 1 : chunk_bytes).run(sax);
}

}  // namespace octolod
