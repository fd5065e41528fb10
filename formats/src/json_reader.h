// A strict JSON reader (RFC 8259) that drives an nlohmann::json_sax handler with the events
// nlohmann's own sax_parse sends for the same text, about 3x faster: the manifest of a 100M-triangle
// tree is 180 MB of JSON, and nlohmann's lexer (a virtual call and a token-buffer push per
// character, strtod per number) was most of the time of opening a tree. Here the bytes come in
// chunks from a buffer, strings are copied a run at a time, and numbers are converted with
// std::from_chars (correctly rounded, locale-independent).
//
// What it accepts is what nlohmann accepts in strict mode: one value with optional whitespace
// around it and an optional UTF-8 byte order mark before it; strings of valid UTF-8 (RFC 3629
// ranges) with no unescaped control character, \u escapes as UTF-8 (surrogates in pairs only);
// integers that fit 64 bits reported as number_unsigned (>= 0) or number_integer (< 0), other
// numbers (fractions, exponents, larger integers) as number_float with their text, an overflow
// to infinity an error. Nesting depth is bounded only by memory (no recursion).
#pragma once

#include <cstddef>
#include <cstdint>
#include <istream>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

namespace octolod {

struct JsonReadResult {
  // Empty when the text is one JSON value (or the handler stopped the read); else what is wrong
  // and where: "syntax error at line 12, column 5 (byte 1234): expected ',' or '}' after an object member".
  std::string error;
  // The handler returned false from an event: the read stopped there.
  bool stopped = false;
};

// Reads the whole of `text`.
JsonReadResult read_json(std::string_view text, nlohmann::json_sax<nlohmann::json>& sax);

// Reads from `in` until its end, `chunk_bytes` (> 0) at a time: memory is one chunk plus the
// longest string or number. A stream that fails before its end (in.bad()) ends the text there:
// the caller checks the stream.
JsonReadResult read_json(std::istream& in, nlohmann::json_sax<nlohmann::json>& sax,
                         std::size_t chunk_bytes = std::size_t{1} << 20);

}  // namespace octolod
