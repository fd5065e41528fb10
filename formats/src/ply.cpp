// PLY syntax shared by the reader and the writer (seed 4.2.1 reads PLY input): scalar type
// names, header parsing and header formatting. See ply_header.h.
#include "octolod/formats/ply.h"

#include <algorithm>
#include <array>
#include <charconv>
#include <cstring>
#include <string>
#include <string_view>
#include <vector>

#include "ply_header.h"

namespace octolod {

std::string_view to_string(PlyFormat format) {
  switch (format) {
    case PlyFormat::ascii: return "ascii";
    case PlyFormat::binary_little_endian: return "binary_little_endian";
    case PlyFormat::binary_big_endian: return "binary_big_endian";
  }
  return "unknown";
}

namespace ply {
namespace {

struct TypeName {
  std::string_view name;
  ScalarType type;
};
constexpr std::array<TypeName, 16> kTypeNames{{
    {"char", ScalarType::int8},      {"uchar", ScalarType::uint8},
    {"short", ScalarType::int16},    {"ushort", ScalarType::uint16},
    {"int", ScalarType::int32},      {"uint", ScalarType::uint32},
    {"float", ScalarType::float32},  {"double", ScalarType::float64},
    {"int8", ScalarType::int8},      {"uint8", ScalarType::uint8},
    {"int16", ScalarType::int16},    {"uint16", ScalarType::uint16},
    {"int32", ScalarType::int32},    {"uint32", ScalarType::uint32},
    {"float32", ScalarType::float32}, {"float64", ScalarType::float64},
}};

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

std::vector<std::string_view> split_words(std::string_view line) {
  std::vector<std::string_view> words;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && is_space(line[i])) ++i;
    const std::size_t start = i;
    while (i < line.size() && !is_space(line[i])) ++i;
    if (i > start) words.push_back(line.substr(start, i - start));
  }
  return words;
}

// Quotes a piece of header text for a message, cut short and with unprintable bytes escaped.
std::string quote_text(std::string_view text) {
  constexpr std::size_t kMaxShown = 40;
  std::string out = "'";
  for (std::size_t i = 0; i < text.size() && i < kMaxShown; ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    if (c >= 0x20 && c < 0x7f) {
      out += static_cast<char>(c);
    } else {
      constexpr char kHex[] = "0123456789abcdef";
      out += "\\x";
      out += kHex[c >> 4];
      out += kHex[c & 15];
    }
  }
  if (text.size() > kMaxShown) out += "...";
  return out + "'";
}

// Reads header lines from a FileBuffer, counting lines and bytes and enforcing kMaxHeaderBytes.
class HeaderLines {
 public:
  explicit HeaderLines(FileBuffer& in) : in_(in) {}

  // The next line without its "\n" / "\r\n"; false when the file ends first.
  Result<bool> next(std::string& line) {
    line.clear();
    for (;;) {
      OCTOLOD_RETURN_IF_ERROR(in_.fill(1));
      if (in_.available() == 0) return false;
      const char* data = in_.data();
      const auto* newline = static_cast<const char*>(std::memchr(data, '\n', in_.available()));
      const std::size_t take = newline != nullptr ? static_cast<std::size_t>(newline - data) + 1
                                                  : in_.available();
      if (bytes_ + take > kMaxHeaderBytes)
        return bad_input_error(message_at_line(
            in_.path(), line_number_ + 1,
            "header exceeds 1 MiB without end_header (is this a PLY file?)"));
      line.append(data, newline != nullptr ? take - 1 : take);
      in_.consume(take);
      bytes_ += take;
      if (newline != nullptr) break;
    }
    ++line_number_;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    return true;
  }

  std::uint64_t line_number() const { return line_number_; }
  std::uint64_t bytes() const { return bytes_; }

 private:
  FileBuffer& in_;
  std::uint64_t line_number_ = 0;
  std::uint64_t bytes_ = 0;
};

std::optional<PlyFormat> parse_format_name(std::string_view name) {
  if (name == "ascii") return PlyFormat::ascii;
  if (name == "binary_little_endian") return PlyFormat::binary_little_endian;
  if (name == "binary_big_endian") return PlyFormat::binary_big_endian;
  return std::nullopt;
}

}  // namespace

std::optional<ScalarType> parse_scalar_type(std::string_view name) {
  for (const TypeName& t : kTypeNames)
    if (t.name == name) return t.type;
  return std::nullopt;
}

std::string_view to_string(ScalarType type) {
  for (const TypeName& t : kTypeNames)
    if (t.type == type) return t.name;
  return "unknown";
}

int Element::find(std::string_view property_name) const {
  for (std::size_t i = 0; i < properties.size(); ++i)
    if (properties[i].name == property_name) return static_cast<int>(i);
  return -1;
}

std::string message_at_line(const std::string& path, std::uint64_t line, std::string_view what) {
  return path + ": line " + std::to_string(line) + ": " + std::string(what);
}

std::string message_at_offset(const std::string& path, std::uint64_t offset,
                              std::string_view what) {
  return path + ": byte offset " + std::to_string(offset) + ": " + std::string(what);
}

Result<Header> parse_header(FileBuffer& in) {
  const std::string& path = in.path();
  // Check the magic before looking for a newline: a binary file that is not a PLY should fail
  // on its first bytes, not after a megabyte of searching.
  OCTOLOD_RETURN_IF_ERROR(in.fill(4));
  const std::string_view start(in.data(), std::min<std::size_t>(in.available(), 4));
  if (start != "ply\n" && start != "ply\r")
    return bad_input_error(message_at_line(
        path, 1,
        in.available() == 0 ? std::string("empty file, expected the 'ply' magic line")
                            : "missing 'ply' magic, the file starts with " + quote_text(start)));

  HeaderLines lines(in);
  Header header;
  std::string line;
  bool have_format = false;
  auto error = [&](const std::string& what) {
    return bad_input_error(message_at_line(path, lines.line_number(), what));
  };

  Result<bool> got = lines.next(line);  // the magic, checked above
  if (!got.ok()) return got.status();
  if (line.rfind("ply\r", 0) == 0 && line.size() > 4)  // lines split at LF only: "ply\rformat ..."
    return bad_input_error(message_at_line(
        path, 1, "the header's lines end in a bare CR (classic Mac OS); PLY lines end in LF or CR LF"));
  if (line != "ply") return error("missing 'ply' magic, the first line is " + quote_text(line));

  for (;;) {
    got = lines.next(line);
    if (!got.ok()) return got.status();
    if (!got.value())
      return bad_input_error(message_at_line(path, lines.line_number(),
                                             "missing end_header: the file ends inside the header"));
    const std::vector<std::string_view> words = split_words(line);
    if (words.empty()) continue;
    const std::string_view keyword = words[0];

    if (keyword == "comment") {
      const std::size_t at = line.find("comment") + 7;
      header.comments.push_back(line.substr(at < line.size() ? at + 1 : at));
      continue;
    }
    if (keyword == "obj_info") continue;
    if (!have_format && keyword != "format")
      return error("expected the format line after 'ply', found " + quote_text(line));

    if (keyword == "format") {
      if (have_format) return error("second format line");
      const auto format = words.size() == 3 ? parse_format_name(words[1]) : std::nullopt;
      if (!format)
        return error("bad format line " + quote_text(line) +
                     ": expected 'format ascii|binary_little_endian|binary_big_endian 1.0'");
      if (words[2] != "1.0" && words[2] != "1")
        return unsupported_error(message_at_line(
            path, lines.line_number(), "PLY version " + quote_text(words[2]) + " is not supported (only 1.0)"));
      header.format = *format;
      have_format = true;
    } else if (keyword == "element") {
      std::uint64_t count = 0;
      if (words.size() != 3)
        return error("bad element line " + quote_text(line) + ": expected 'element <name> <count>'");
      const auto [end, ec] = std::from_chars(words[2].data(), words[2].data() + words[2].size(), count);
      if (ec != std::errc() || end != words[2].data() + words[2].size())
        return error("bad element count " + quote_text(words[2]) + " for element " + quote_text(words[1]));
      for (const Element& e : header.elements)
        if (e.name == words[1]) return error("element " + quote_text(words[1]) + " declared twice");
      header.elements.push_back(Element{std::string(words[1]), count, {}, lines.line_number()});
    } else if (keyword == "property") {
      if (header.elements.empty()) return error("property before any element");
      Property property;
      if (words.size() >= 2 && words[1] == "list") {
        if (words.size() != 5)
          return error("bad list property " + quote_text(line) +
                       ": expected 'property list <count type> <item type> <name>'");
        const auto count_type = parse_scalar_type(words[2]);
        const auto item_type = parse_scalar_type(words[3]);
        if (!count_type) return error("unknown property type " + quote_text(words[2]));
        if (!item_type) return error("unknown property type " + quote_text(words[3]));
        if (!is_integer(*count_type))
          return error("list count type " + quote_text(words[2]) + " is not an integer type");
        property = Property{std::string(words[4]), *item_type, true, *count_type};
      } else {
        if (words.size() != 3)
          return error("bad property line " + quote_text(line) + ": expected 'property <type> <name>'");
        const auto type = parse_scalar_type(words[1]);
        if (!type) return error("unknown property type " + quote_text(words[1]));
        property = Property{std::string(words[2]), *type, false, ScalarType::uint8};
      }
      Element& element = header.elements.back();
      if (element.find(property.name) >= 0)
        return error("property " + quote_text(property.name) + " declared twice in element " +
                     quote_text(element.name));
      element.properties.push_back(std::move(property));
    } else if (keyword == "end_header") {
      if (words.size() != 1) return error("unexpected text after end_header");
      break;
    } else {
      return error("unknown header keyword " + quote_text(keyword));
    }
  }
  header.bytes = lines.bytes();
  header.lines = lines.line_number();
  return header;
}

std::string format_header(const Header& header) {
  std::string text = "ply\nformat ";
  text += to_string(header.format);
  text += " 1.0\n";
  for (const std::string& comment : header.comments) text += "comment " + comment + "\n";
  for (const Element& element : header.elements) {
    text += "element " + element.name + " " + std::to_string(element.count) + "\n";
    for (const Property& p : element.properties) {
      text += "property ";
      if (p.is_list) {
        text += "list ";
        text += to_string(p.count_type);
        text += ' ';
      }
      text += to_string(p.type);
      text += ' ' + p.name + '\n';
    }
  }
  return text + "end_header\n";
}

}  // namespace ply
}  // namespace octolod
