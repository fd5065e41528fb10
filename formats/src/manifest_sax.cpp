// ManifestSax, see manifest_sax.h.
#include "manifest_sax.h"

#include <array>
#include <string_view>
#include <utility>

namespace octolod {
namespace {

using nlohmann::json;

// Members of a node, as bits of ManifestSax::node_seen_.
enum NodeMember : std::uint32_t {
  kPath = 1u << 0,
  kDepth = 1u << 1,
  kParent = 1u << 2,
  kChildren = 1u << 3,
  kCellMin = 1u << 4,
  kCellMax = 1u << 5,
  kBoundsMin = 1u << 6,
  kBoundsMax = 1u << 7,
  kSourceTriangles = 1u << 8,
  kLods = 1u << 9,
  kAllNodeMembers = (1u << 10) - 1,
};
// Members of a LOD, as bits of ManifestSax::lod_seen_.
enum LodMember : std::uint32_t {
  kTriangles = 1u << 0,
  kVertices = 1u << 1,
  kError = 1u << 2,
  kBytes = 1u << 3,
  kFile = 1u << 4,
  kAllLodMembers = (1u << 5) - 1,
};

}  // namespace

// ---- the document's events: the header's members into document_, nodes to the node reader ----

bool ManifestSax::scalar(const Scalar& value, json&& as_json) {
  switch (mode_) {
    case Mode::header:
      add_to_document(std::move(as_json), false);
      return true;
    case Mode::nodes:  // a bare value in "nodes"
      if (node_error_.empty()) node_error_ = "\"nodes\" holds a value that is not an object";
      return true;
    case Mode::node:
      node_scalar(value);
      return true;
    case Mode::node_skipped:
      return true;
  }
  return true;
}

bool ManifestSax::open(bool object, std::size_t /*elements*/) {
  ++depth_;
  switch (mode_) {
    case Mode::header:
      if (depth_ == 2 && nodes_key_ && !object) {  // "nodes": [ ... ]
        add_to_document(json::array(), false);
        mode_ = Mode::nodes;
      } else {
        add_to_document(object ? json::object() : json::array(), true);
      }
      return true;
    case Mode::nodes:
      if (!object || !node_error_.empty()) {
        if (!object && node_error_.empty()) node_error_ = "\"nodes\" holds a value that is not an object";
        mode_ = Mode::node_skipped;
        return true;
      }
      mode_ = Mode::node;
      start_node();
      return true;
    case Mode::node:
      node_open(object);
      return true;
    case Mode::node_skipped:
      return true;
  }
  return true;
}

bool ManifestSax::close() {
  switch (mode_) {
    case Mode::header:
      if (!open_.empty()) open_.pop_back();
      break;
    case Mode::nodes:  // the end of "nodes"
      mode_ = Mode::header;
      break;
    case Mode::node:
      node_close();
      if (depth_ == 3) mode_ = Mode::nodes;
      break;
    case Mode::node_skipped:
      if (depth_ == 3) mode_ = Mode::nodes;
      break;
  }
  --depth_;
  return true;
}

void ManifestSax::add_to_document(json&& value, bool container) {
  json* added = nullptr;
  if (open_.empty()) {
    document_ = std::move(value);
    added = &document_;
  } else if (open_.back()->is_array()) {
    open_.back()->push_back(std::move(value));
    added = &open_.back()->back();
  } else {
    added = &((*open_.back())[key_] = std::move(value));
  }
  if (container) open_.push_back(added);
}

bool ManifestSax::null() { return scalar({}, json(nullptr)); }
bool ManifestSax::boolean(bool value) { return scalar({}, json(value)); }
bool ManifestSax::binary(binary_t& value) { return scalar({}, json::binary(value)); }

bool ManifestSax::number_integer(number_integer_t value) {
  Scalar s;
  s.kind = Scalar::Kind::integer;
  s.integer = value;
  return scalar(s, mode_ == Mode::header ? json(value) : json());
}

bool ManifestSax::number_unsigned(number_unsigned_t value) {
  Scalar s;
  s.kind = Scalar::Kind::unsigned_integer;
  s.unsigned_integer = value;
  return scalar(s, mode_ == Mode::header ? json(value) : json());
}

bool ManifestSax::number_float(number_float_t value, const string_t& /*text*/) {
  Scalar s;
  s.kind = Scalar::Kind::floating;
  s.floating = value;
  return scalar(s, mode_ == Mode::header ? json(value) : json());
}

bool ManifestSax::string(string_t& value) {
  Scalar s;
  s.kind = Scalar::Kind::string;
  s.text = &value;
  return scalar(s, mode_ == Mode::header ? json(value) : json());
}

bool ManifestSax::start_object(std::size_t elements) { return open(true, elements); }
bool ManifestSax::start_array(std::size_t elements) { return open(false, elements); }
bool ManifestSax::end_object() { return close(); }
bool ManifestSax::end_array() { return close(); }

bool ManifestSax::key(string_t& value) {
  if (mode_ == Mode::header) {
    key_ = value;
    nodes_key_ = depth_ == 1 && value == "nodes";
  } else if (mode_ == Mode::node) {
    node_key(value);
  }
  return true;
}

bool ManifestSax::parse_error(std::size_t /*position*/, const std::string& /*last_token*/,
                              const nlohmann::detail::exception& /*error*/) {
  return false;  // (nlohmann's parser is not used: read_json reports syntax errors)
}

// ---- one node -----------------------------------------------------------------------------
// Levels inside a node: 1 its members, 2 the elements of "children" and "lods" and the members
// of "cell" and "bounds", 3 the elements of their "min" and "max" and the members of a LOD.
// Members the format does not define (child_mask, which the children already give) are skipped
// whatever their value; a member it defines with a value of another kind fails the node.

namespace {

using Key = ManifestSax::Key;

constexpr std::pair<std::string_view, Key> kKeys[] = {
    {"path", Key::path},         {"depth", Key::depth},
    {"parent", Key::parent},     {"children", Key::children},
    {"cell", Key::cell},         {"bounds", Key::bounds},
    {"source_triangles", Key::source_triangles}, {"lods", Key::lods},
    {"min", Key::min},           {"max", Key::max},
    {"triangles", Key::triangles}, {"vertices", Key::vertices},
    {"error", Key::error},       {"bytes", Key::bytes},
    {"file", Key::file},
};

Key key_of(std::string_view text) {
  for (const auto& [name, key] : kKeys)
    if (name == text) return key;
  return Key::other;
}

std::string_view name_of(Key key) {
  for (const auto& [name, k] : kKeys)
    if (k == key) return name;
  return "?";
}

std::string quoted(Key key) { return "\"" + std::string(name_of(key)) + "\""; }

// The members the bits of node_seen_ and lod_seen_ stand for, in bit order: a key, or a box's
// key and its "min" or "max".
constexpr std::array<std::pair<Key, Key>, 10> kNodeMembers{{{Key::path, Key::other},
                                                            {Key::depth, Key::other},
                                                            {Key::parent, Key::other},
                                                            {Key::children, Key::other},
                                                            {Key::cell, Key::min},
                                                            {Key::cell, Key::max},
                                                            {Key::bounds, Key::min},
                                                            {Key::bounds, Key::max},
                                                            {Key::source_triangles, Key::other},
                                                            {Key::lods, Key::other}}};
constexpr std::array<std::pair<Key, Key>, 5> kLodMembers{{{Key::triangles, Key::other},
                                                          {Key::vertices, Key::other},
                                                          {Key::error, Key::other},
                                                          {Key::bytes, Key::other},
                                                          {Key::file, Key::other}}};

// The first member whose bit `seen` lacks, quoted ("cell.min" for a box member).
template <std::size_t N>
std::string first_missing(std::uint32_t seen, const std::array<std::pair<Key, Key>, N>& members) {
  for (std::size_t i = 0; i < N; ++i)
    if (!(seen & (1u << i))) {
      const auto [key, part] = members[i];
      return "\"" + std::string(name_of(key)) + (part == Key::other ? "" : "." + std::string(name_of(part))) + "\"";
    }
  return {};
}

}  // namespace

void ManifestSax::start_node() {
  node_ = NodeInfo{};
  node_seen_ = 0;
  lod_seen_ = 0;
  skip_depth_ = 0;
  for (Key& key : node_key_) key = Key::other;
  for (std::size_t& index : node_index_) index = 0;
}

void ManifestSax::fail(const std::string& what) {
  if (node_error_.empty()) node_error_ = "node " + std::to_string(nodes_.size()) + ": " + what;
  mode_ = Mode::node_skipped;
  skip_depth_ = 0;
}

void ManifestSax::skip() { skip_depth_ = depth_; }

void ManifestSax::node_key(std::string_view text) {
  const std::size_t level = depth_ - 2;
  if (skip_depth_ == 0 && level < 4) node_key_[level] = key_of(text);
}

// "cell.min" and the like: the box member being read
std::string ManifestSax::box_member() const {
  return "\"" + std::string(name_of(node_key_[1])) + "." + std::string(name_of(node_key_[2])) + "\"";
}

void ManifestSax::node_scalar(const Scalar& value) {
  if (skip_depth_ != 0) return;
  const std::size_t level = depth_ - 2;
  const bool is_signed = value.kind == Scalar::Kind::integer;
  const bool is_unsigned = value.kind == Scalar::Kind::unsigned_integer;
  const bool is_number = is_signed || is_unsigned || value.kind == Scalar::Kind::floating;
  const double number = is_signed ? static_cast<double>(value.integer)
                                  : is_unsigned ? static_cast<double>(value.unsigned_integer) : value.floating;
  auto integer = [&](auto& out, Key key) {
    if (!integer_in_range(value.integer, value.unsigned_integer, is_signed, is_unsigned, out))
      fail(quoted(key) + " is not an integer in range");
  };
  const Key member = node_key_[1];
  if (level == 1) {
    switch (member) {
      case Key::path:
        if (value.kind != Scalar::Kind::string) return fail("\"path\" is not a string");
        node_.path = std::move(*value.text);
        node_seen_ |= kPath;
        return;
      case Key::depth:
        integer(node_.depth, member);
        node_seen_ |= kDepth;
        return;
      case Key::parent:
        integer(node_.parent, member);
        node_seen_ |= kParent;
        return;
      case Key::source_triangles:
        integer(node_.source_triangles, member);
        node_seen_ |= kSourceTriangles;
        return;
      case Key::cell:
      case Key::bounds:
        return fail(quoted(member) + " is not an object");
      case Key::children:
      case Key::lods:
        return fail(quoted(member) + " is not an array");
      default:
        return;
    }
  }
  if (level == 2) {
    if (member == Key::children) {
      if (node_index_[2] >= 8) return fail("\"children\" has more than 8 elements");
      integer(node_.children[node_index_[2]++], member);
    } else if (member == Key::lods) {
      fail("\"lods\" holds a value that is not an object");
    } else if (node_key_[2] == Key::min || node_key_[2] == Key::max) {  // of "cell" or "bounds"
      fail(box_member() + " is not an array");
    }
    return;
  }
  if (level != 3) return;
  if (member == Key::cell || member == Key::bounds) {
    if (!is_number) return fail(box_member() + " holds a value that is not a number");
    if (node_index_[3] >= 3) return fail(box_member() + " has more than 3 elements");
    if (!within_float_range(number))
      return fail(box_member() + " holds a number beyond the float range");
    Bounds& box = member == Key::cell ? node_.cell : node_.bounds;
    (node_key_[2] == Key::min ? box.min : box.max)[node_index_[3]++] = static_cast<float>(number);
    return;
  }
  if (member != Key::lods) return;
  LodInfo& lod = node_.lods.back();
  const Key field = node_key_[3];
  switch (field) {
    case Key::triangles:
      integer(lod.triangles, field);
      lod_seen_ |= kTriangles;
      return;
    case Key::vertices:
      integer(lod.vertices, field);
      lod_seen_ |= kVertices;
      return;
    case Key::error:
      if (!is_number) return fail("\"error\" is not a number");
      lod.error = number;
      lod_seen_ |= kError;
      return;
    case Key::bytes:
      integer(lod.bytes, field);
      lod_seen_ |= kBytes;
      return;
    case Key::file:
      if (value.kind != Scalar::Kind::string) return fail("\"file\" is not a string");
      lod.file = std::move(*value.text);
      lod_seen_ |= kFile;
      return;
    default:
      return;
  }
}

void ManifestSax::node_open(bool object) {
  if (skip_depth_ != 0) return;
  const std::size_t level = depth_ - 2;  // of the container just opened
  const Key member = node_key_[1];
  const bool box = member == Key::cell || member == Key::bounds;
  if (level == 2) {
    if (!box && member != Key::children && member != Key::lods) return skip();
    if (object != box) return fail(quoted(member) + " is not " + (box ? "an object" : "an array"));
    node_index_[2] = 0;
    node_key_[2] = Key::other;
    return;
  }
  if (level == 3) {
    if (member == Key::children) return fail("\"children\" holds a value that is not an integer");
    if (member == Key::lods) {
      if (!object) return fail("\"lods\" holds a value that is not an object");
      node_.lods.emplace_back();
      lod_seen_ = 0;
      node_key_[3] = Key::other;
      return;
    }
    if (node_key_[2] != Key::min && node_key_[2] != Key::max) return skip();
    if (object) return fail(box_member() + " is not an array");
    node_index_[3] = 0;
    return;
  }
  // level 4 and deeper: an element of "min" / "max", or the value of a LOD's member
  if (box) return fail(box_member() + " holds a value that is not a number");
  if (level == 4 && node_key_[3] != Key::other) return fail(quoted(node_key_[3]) + " is not a scalar");
  skip();
}

void ManifestSax::node_close() {
  if (skip_depth_ != 0) {
    if (depth_ == skip_depth_) skip_depth_ = 0;
    return;
  }
  const std::size_t level = depth_ - 2;  // of the container closing
  const Key member = node_key_[1];
  if (level == 1) {
    if (node_seen_ != kAllNodeMembers) return fail("no " + first_missing(node_seen_, kNodeMembers));
    nodes_.push_back(std::move(node_));
  } else if (level == 2) {
    if (member == Key::children) {
      if (node_index_[2] != 8) return fail("\"children\" does not have 8 elements");
      node_seen_ |= kChildren;
    } else if (member == Key::lods) {
      node_seen_ |= kLods;
    }
  } else if (level == 3) {
    if (member == Key::lods) {
      if (lod_seen_ != kAllLodMembers)
        return fail("lod " + std::to_string(node_.lods.size() - 1) + ": no " + first_missing(lod_seen_, kLodMembers));
    } else {
      if (node_index_[3] != 3) return fail(box_member() + " does not have 3 elements");
      const bool min = node_key_[2] == Key::min;
      node_seen_ |= member == Key::cell ? (min ? kCellMin : kCellMax) : (min ? kBoundsMin : kBoundsMax);
    }
  }
}

}  // namespace octolod
