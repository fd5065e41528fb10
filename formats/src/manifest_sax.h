// The SAX handler that reads manifest.json (manifest.cpp): every element of "nodes" goes straight
// into a NodeInfo as the parser reports it, without a JSON value per node; the other members (a
// few hundred bytes) are collected into a JSON document, "nodes" in it an empty array, and read
// from there. A 100M-triangle tree's manifest holds 212K nodes: a value per node (nlohmann's
// objects are maps of strings) was most of the time of opening a tree.
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "octolod/formats/manifest.h"

namespace octolod {

// A JSON integer (a signed or an unsigned one, as the parser reports it) as a T: false when it
// is neither or out of T's range. nlohmann's get<T>() casts whatever number it holds, which is
// undefined behaviour beyond T's range (a float such as 2e68 included).
template <class T>
bool integer_in_range(std::int64_t integer, std::uint64_t unsigned_integer, bool is_signed, bool is_unsigned, T& out) {
  if (is_unsigned && unsigned_integer <= static_cast<std::uint64_t>(std::numeric_limits<T>::max())) {
    out = static_cast<T>(unsigned_integer);
    return true;
  }
  if (is_signed && std::numeric_limits<T>::is_signed &&
      integer >= static_cast<std::int64_t>(std::numeric_limits<T>::min()) &&
      integer <= static_cast<std::int64_t>(std::numeric_limits<T>::max())) {
    out = static_cast<T>(integer);
    return true;
  }
  return false;
}

// Whether a number converts to float: a float cast beyond the float range is undefined behaviour.
inline bool within_float_range(double x) { return std::fabs(x) <= std::numeric_limits<float>::max(); }

class ManifestSax : public nlohmann::json_sax<nlohmann::json> {
 public:
  // The keys of a node's members, of "cell" / "bounds" and of a LOD; other for any other key.
  enum class Key : std::uint8_t {
    other, path, depth, parent, children, cell, bounds, source_triangles, lods, min, max,
    triangles, vertices, error, bytes, file,
  };

  // Nodes go to `nodes`, in document order.
  explicit ManifestSax(std::vector<NodeInfo>& nodes) : nodes_(nodes) {}

  // After the read (read_json, which reports syntax errors itself): the document without its
  // nodes (null when it was not an object) and the first node that could not be read ("node 3:
  // ..."; empty when none).
  const nlohmann::json& document() const { return document_; }
  const std::string& node_error() const { return node_error_; }

  bool null() override;
  bool boolean(bool value) override;
  bool number_integer(number_integer_t value) override;
  bool number_unsigned(number_unsigned_t value) override;
  bool number_float(number_float_t value, const string_t& text) override;
  bool string(string_t& value) override;
  bool binary(binary_t& value) override;
  bool start_object(std::size_t elements) override;
  bool key(string_t& value) override;
  bool end_object() override;
  bool start_array(std::size_t elements) override;
  bool end_array() override;
  bool parse_error(std::size_t position, const std::string& last_token,
                   const nlohmann::detail::exception& error) override;

 private:
  // One scalar as the parser reported it.
  struct Scalar {
    enum class Kind { integer, unsigned_integer, floating, string, other } kind = Kind::other;
    std::int64_t integer = 0;
    std::uint64_t unsigned_integer = 0;
    double floating = 0.0;
    std::string* text = nullptr;  // the parser's string, valid during the event
  };
  // Where in the document the parser is.
  enum class Mode { header, nodes, node, node_skipped };

  bool scalar(const Scalar& value, nlohmann::json&& as_json);
  bool open(bool object, std::size_t elements);
  bool close();

  // header mode: the document being built
  void add_to_document(nlohmann::json&& value, bool container);

  // node mode (depth_ >= 3): the node being read
  void start_node();
  void node_key(std::string_view text);
  std::string box_member() const;
  void node_scalar(const Scalar& value);
  void node_open(bool object);
  void node_close();
  void fail(const std::string& what);  // the current node cannot be read
  void skip();                         // the container just opened is not read

  std::vector<NodeInfo>& nodes_;
  nlohmann::json document_;
  std::vector<nlohmann::json*> open_;  // the document's containers being filled
  std::string key_;                    // the key of the document's next member
  std::string node_error_;
  Mode mode_ = Mode::header;
  std::size_t depth_ = 0;  // containers open in the whole document
  bool nodes_key_ = false; // the document's next member is "nodes"

  // The node being read: the key at each level inside it (level 1 = the node's own members),
  // the index of the next element of the array open at each level, and the members seen.
  NodeInfo node_;
  Key node_key_[4] = {};
  std::size_t node_index_[4] = {};
  std::uint32_t node_seen_ = 0;
  std::uint32_t lod_seen_ = 0;
  std::size_t skip_depth_ = 0;  // depth_ of the container being skipped, 0 when none
};

}  // namespace octolod
