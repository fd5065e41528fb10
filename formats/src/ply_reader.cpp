// PLY semantics and streaming decode (seed 4.2.1: the model is read in portions, vertices and
// faces written out as they come, so memory never depends on the file size). ply.cpp parses the
// header syntax and ply_body.h reads body values; this file decides what the properties mean
// (positions, normals, colours, texture coordinates, polygons), checks the declared counts
// against the file size before anything is allocated, and decodes batches, with fast paths for
// the common binary layouts (fixed-size vertices, uchar-counted int index lists).
#include "octolod/formats/ply_reader.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cctype>
#include <cmath>
#include <initializer_list>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <unordered_map>
#include <utility>
#include <vector>

#include "ply_body.h"
#include "ply_file_buffer.h"
#include "ply_header.h"

namespace octolod {
namespace {

using ply::ScalarType;

constexpr std::uint64_t kMaxPolygonVertices = std::uint64_t{1} << 20;
constexpr std::size_t kMinBatchBytes = 4096;
constexpr std::uint32_t kNoSlot = std::numeric_limits<std::uint32_t>::max();

enum class Role { skip, vertices, faces };

struct PropertyPlan {
  ply::Property property;
  std::uint32_t slot = kNoSlot;  // vertices: float offset of the value within a decoded vertex;
                                 // faces' colours: 0, 1, 2 for red, green, blue
  double divisor = 0.0;          // integer colours: divided by their type's maximum; 0 = as is
  int axis = -1;                 // positions: 0, 1, 2 for x, y, z (less the reader's origin)
  bool is_index_list = false;    // faces: the vertex_indices / vertex_index list
  bool is_uv_list = false;       // faces: the texcoord list (u, v per corner)
  std::size_t offset = 0;        // binary elements without lists: byte offset in the entry
};

struct ElementPlan {
  std::string name;
  std::uint64_t count = 0;
  Role role = Role::skip;
  std::vector<PropertyPlan> properties;
  bool fixed_size = true;  // no list properties: every binary entry has `stride` bytes
  std::size_t stride = 0;
};

struct Plan {
  PlyInfo info;
  std::vector<ElementPlan> elements;
};

// The first complete group of scalar properties among `groups` (each a set of names), as
// property indices; nullopt when none is complete.
template <std::size_t N>
std::optional<std::array<int, N>> find_group(const ply::Element& element,
                                             std::initializer_list<std::array<const char*, N>> groups) {
  for (const auto& names : groups) {
    std::array<int, N> found{};
    bool complete = true;
    for (std::size_t i = 0; i < N; ++i) {
      found[i] = element.find(names[i]);
      if (found[i] < 0 || element.properties[static_cast<std::size_t>(found[i])].is_list)
        complete = false;
    }
    if (complete) return found;
  }
  return std::nullopt;
}

// The first complete colour group of `element`.
std::optional<std::array<int, 3>> find_color(const ply::Element& element) {
  return find_group<3>(element, {{"red", "green", "blue"}, {"diffuse_red", "diffuse_green", "diffuse_blue"}});
}

// Colour properties `color` of `plan` to slots first_slot + 0, 1, 2, integer types divided by
// their maximum; info.color_type from the red's type.
void plan_color(const ply::Element& element, const std::array<int, 3>& color, std::uint32_t first_slot,
                ElementPlan& plan, PlyInfo& info) {
  for (std::uint32_t i = 0; i < 3; ++i) {
    PropertyPlan& p = plan.properties[static_cast<std::size_t>(color[i])];
    p.slot = first_slot + i;
    if (ply::is_integer(p.property.type)) p.divisor = ply::max_value(p.property.type);
  }
  const ScalarType red = element.properties[static_cast<std::size_t>(color[0])].type;
  info.color_type = ply::is_integer(red) ? PlyColorType::uchar : PlyColorType::float32;
}

// Vertex semantics: which properties become which floats of VertexLayout. Attributes the faces
// give their corners (info.corners, planned before) are in the layout, and the vertices' own
// are skipped.
Status plan_vertices(const ply::Element& element, const std::string& path, ElementPlan& plan,
                     PlyInfo& info) {
  auto error = [&](const std::string& what) {
    return bad_input_error(ply::message_at_line(path, element.line, what));
  };
  for (const char* name : {"x", "y", "z"}) {
    const int i = element.find(name);
    if (i < 0) return error(std::string("element 'vertex' has no property '") + name + "'");
    if (element.properties[static_cast<std::size_t>(i)].is_list)
      return error(std::string("vertex property '") + name + "' is a list");
  }
  const auto position = find_group<3>(element, {{"x", "y", "z"}});
  const auto normal = find_group<3>(element, {{"nx", "ny", "nz"}});
  const auto color = info.corners.color ? std::nullopt : find_color(element);
  const auto uv = info.corners.uv ? std::nullopt
                                  : find_group<2>(element, {{"u", "v"},
                                                            {"s", "t"},
                                                            {"texture_u", "texture_v"},
                                                            {"texture_s", "texture_t"}});
  info.layout = VertexLayout{normal.has_value(), color.has_value() || info.corners.color,
                             uv.has_value() || info.corners.uv};

  auto assign = [&](int property, std::uint32_t slot) {
    plan.properties[static_cast<std::size_t>(property)].slot = slot;
  };
  for (std::uint32_t i = 0; i < 3; ++i) {
    PropertyPlan& p = plan.properties[static_cast<std::size_t>((*position)[i])];
    p.slot = VertexLayout::position_offset() + i;
    p.axis = static_cast<int>(i);
    info.double_positions = info.double_positions || p.property.type == ScalarType::float64;
  }
  if (normal)
    for (std::uint32_t i = 0; i < 3; ++i) assign((*normal)[i], VertexLayout::normal_offset() + i);
  if (color) plan_color(element, *color, info.layout.color_offset(), plan, info);
  if (uv)
    for (std::uint32_t i = 0; i < 2; ++i) assign((*uv)[i], info.layout.uv_offset() + i);
  return {};
}

// Face semantics: the index list, whose items must be integers, the texture coordinates per
// corner (`texcoord`, MeshLab's and photogrammetry tools' name), whose items must be floats, and
// a colour per face.
Status plan_faces(const ply::Element& element, const std::string& path, ElementPlan& plan,
                  PlyInfo& info) {
  int list = element.find("vertex_indices");
  if (list < 0) list = element.find("vertex_index");
  auto error = [&](const std::string& what) {
    return bad_input_error(ply::message_at_line(path, element.line, what));
  };
  if (list < 0) return error("element 'face' has no list property vertex_indices or vertex_index");
  PropertyPlan& p = plan.properties[static_cast<std::size_t>(list)];
  if (!p.property.is_list) return error("face property '" + p.property.name + "' is not a list");
  if (!ply::is_integer(p.property.type))
    return error("face property '" + p.property.name + "' has non-integer items (" +
                 std::string(ply::to_string(p.property.type)) + ")");
  p.is_index_list = true;
  if (const auto color = find_color(element)) {
    plan_color(element, *color, 0, plan, info);
    info.corners.color = true;
  }
  const int uvs = element.find("texcoord");
  if (uvs < 0) return {};
  PropertyPlan& t = plan.properties[static_cast<std::size_t>(uvs)];
  if (!t.property.is_list || ply::is_integer(t.property.type))
    return error("face property 'texcoord' is not a list of floats (u, v per corner)");
  t.is_uv_list = true;
  info.corners.uv = true;
  return {};
}

// Bytes an entry needs at least: binary exact scalar sizes; ascii two characters per value
// (a digit and a separator). Index lists hold at least 3 items.
std::uint64_t min_entry_bytes(const ElementPlan& plan, PlyFormat format) {
  std::uint64_t bytes = 0;
  for (const PropertyPlan& p : plan.properties) {
    const std::uint64_t items = p.is_index_list ? 3 : 0;
    if (format == PlyFormat::ascii) {
      bytes += 2 + 2 * items;
    } else if (p.property.is_list) {
      bytes += ply::size_of(p.property.count_type) + items * ply::size_of(p.property.type);
    } else {
      bytes += ply::size_of(p.property.type);
    }
  }
  return bytes;
}

// Declared counts against the file size, before any of them is used: a header claiming 10^12
// vertices in a 200-byte file fails here, with nothing allocated.
Status check_counts(const ply::Header& header, const Plan& plan, std::uint64_t file_size,
                    const std::string& path) {
  const std::uint64_t body = file_size - header.bytes;
  // The last ascii value may end the file without a separator.
  const std::uint64_t allowance = header.format == PlyFormat::ascii ? 1 : 0;
  std::uint64_t total = 0;
  for (std::size_t i = 0; i < plan.elements.size(); ++i) {
    const ElementPlan& element = plan.elements[i];
    const std::uint64_t each = min_entry_bytes(element, header.format);
    std::uint64_t bytes = 0;
    const bool overflow = __builtin_mul_overflow(element.count, each, &bytes) ||
                          __builtin_add_overflow(total, bytes, &total);
    const bool has_faces = std::any_of(element.properties.begin(), element.properties.end(),
                                       [](const PropertyPlan& p) { return p.is_index_list; });
    if (overflow || total > body + allowance)
      return bad_input_error(ply::message_at_line(
          path, header.elements[i].line,
          "element '" + element.name + "' declares " + std::to_string(element.count) +
              " entries of at least " + std::to_string(each) +
              " bytes each, more than the file can hold (" + std::to_string(body) +
              " bytes follow the header): truncated file or corrupt count" +
              (has_faces ? " (or faces of fewer than 3 vertices, which are not polygons)" : "")));
  }
  return {};
}

// The names in the "comment TextureFile <name>" lines of `comments` (keyword in any case).
std::vector<std::string> texture_files(const std::vector<std::string>& comments) {
  constexpr std::string_view kKeyword = "texturefile";
  std::vector<std::string> names;
  for (const std::string& comment : comments) {
    const std::size_t start = comment.find_first_not_of(" \t");
    if (start == std::string::npos || comment.size() - start <= kKeyword.size()) continue;
    const std::string_view rest = std::string_view(comment).substr(start);
    if (!std::equal(kKeyword.begin(), kKeyword.end(), rest.begin(),
                    [](char a, char b) { return a == std::tolower(static_cast<unsigned char>(b)); }))
      continue;
    const std::string_view name = rest.substr(kKeyword.size());
    if (name.front() != ' ' && name.front() != '\t') continue;
    const std::size_t first = name.find_first_not_of(" \t");
    const std::size_t last = name.find_last_not_of(" \t\r");
    if (first != std::string_view::npos) names.emplace_back(name.substr(first, last - first + 1));
  }
  return names;
}

Result<Plan> build_plan(const ply::Header& header, const ply::FileBuffer& in) {
  const std::string& path = in.path();
  Plan plan;
  plan.info.texture_files = texture_files(header.comments);
  plan.info.path = path;
  plan.info.format = header.format;
  plan.info.header_bytes = header.bytes;
  const ply::Element* vertex = nullptr;
  for (const ply::Element& element : header.elements) {
    ElementPlan p;
    p.name = element.name;
    p.count = element.count;
    std::size_t offset = 0;
    for (const ply::Property& property : element.properties) {
      p.properties.push_back(PropertyPlan{.property = property, .offset = offset});
      if (property.is_list) p.fixed_size = false;
      offset += ply::size_of(property.type);
    }
    p.stride = offset;
    if (element.name == "vertex") {
      vertex = &element;
      p.role = Role::vertices;
      plan.info.vertex_count = element.count;
    } else if (element.name == "face") {
      p.role = Role::faces;
      plan.info.face_count = element.count;
    }
    plan.elements.push_back(std::move(p));
  }
  if (vertex == nullptr)
    return bad_input_error(ply::message_at_line(path, header.lines, "the header declares no 'vertex' element"));
  // faces first: what they give their corners decides the vertices' layout
  for (std::size_t i = 0; i < header.elements.size(); ++i)
    if (plan.elements[i].role == Role::faces)
      OCTOLOD_RETURN_IF_ERROR(plan_faces(header.elements[i], path, plan.elements[i], plan.info));
  for (std::size_t i = 0; i < header.elements.size(); ++i)
    if (plan.elements[i].role == Role::vertices)
      OCTOLOD_RETURN_IF_ERROR(plan_vertices(header.elements[i], path, plan.elements[i], plan.info));
  for (const ElementPlan& element : plan.elements) {
    if (element.role == Role::skip) {
      plan.info.skipped.push_back("element " + element.name);
      continue;
    }
    for (const PropertyPlan& p : element.properties)
      if (p.slot == kNoSlot && !p.is_index_list && !p.is_uv_list)
        plan.info.skipped.push_back(element.name + "." + p.property.name);
  }
  OCTOLOD_RETURN_IF_ERROR(check_counts(header, plan, in.file_size(), path));
  if (vertex->count > std::numeric_limits<std::uint32_t>::max())
    return unsupported_error(ply::message_at_line(
        path, vertex->line,
        std::to_string(vertex->count) + " vertices: octolod indexes vertices with 32 bits (at most " +
            std::to_string(std::numeric_limits<std::uint32_t>::max()) + ")"));
  return plan;
}

// Decoding state of the face entry in progress, so a polygon whose fan does not fit the batch
// continues in the next one.
struct FaceProgress {
  bool started = false;       // begin_entry done for the current entry
  std::size_t property = 0;   // next property of the entry
  bool in_list = false;       // inside the index list
  std::uint32_t length = 0;   // its item count
  std::uint32_t done = 0;     // items read
  std::uint32_t first = 0;    // fan centre v0
  std::uint32_t previous = 0;
};

template <class Source>
class StreamReader final : public PlyReader {
 public:
  StreamReader(std::unique_ptr<ply::FileBuffer> in, Source source, Plan plan,
               const PlyReadOptions& options)
      : in_(std::move(in)), source_(std::move(source)), plan_(std::move(plan)),
        batch_bytes_(std::max(options.buffer_bytes, kMinBatchBytes)) {
    info_ = plan_.info;
    if (options.position_origin) info_.position_origin = *options.position_origin;
    else origin_pending_ = options.recentre_double_positions && info_.double_positions;
  }

  Result<PlyBatch> next() override {
    if (!failure_.ok()) return failure_;
    PlyBatch batch;
    Status status = advance(batch);
    if (!status.ok()) {
      failure_ = status;
      return status;
    }
    return batch;
  }

 private:
  Status advance(PlyBatch& batch) {
    while (element_ < plan_.elements.size()) {
      const ElementPlan& element = plan_.elements[element_];
      if (index_ == element.count) {
        ++element_;
        index_ = 0;
        continue;
      }
      if (element.role == Role::skip) {
        OCTOLOD_RETURN_IF_ERROR(skip_element(element));
        continue;
      }
      if (element.role == Role::vertices) {
        std::size_t produced = 0;
        OCTOLOD_RETURN_IF_ERROR(decode_vertices(element, produced));
        batch.kind = PlyBatch::Kind::vertices;
        batch.first = vertices_emitted_;
        batch.vertices = std::span<const float>(vertices_.data(), produced * info_.layout.floats());
        vertices_emitted_ += produced;
        return {};
      }
      std::size_t produced = 0;
      OCTOLOD_RETURN_IF_ERROR(decode_faces(element, produced));
      if (produced == 0) continue;
      batch.kind = PlyBatch::Kind::triangles;
      batch.first = triangles_emitted_;
      batch.triangles = std::span<const std::uint32_t>(triangles_.data(), produced * 3);
      if (info_.corners.any())
        batch.corner_values = std::span<const float>(corner_values_.data(), produced * 3 * info_.corners.floats());
      triangles_emitted_ += produced;
      return {};
    }
    if (!trailing_checked_) {
      OCTOLOD_RETURN_IF_ERROR(source_.check_trailing());
      info_.trailing_bytes = in_->file_size() - std::min(in_->offset(), in_->file_size());
      trailing_checked_ = true;
    }
    batch = PlyBatch{};
    return {};
  }

  Status error_at(std::uint64_t position, const std::string& what) const {
    return bad_input_error(source_.message_at(position, what));
  }

  ply::EntryContext context(const ElementPlan& element) const {
    return ply::EntryContext{&element.name, index_, element.count};
  }

  Status skip_element(const ElementPlan& element) {
    if (element.properties.empty()) {  // entries without values take no bytes, nor lines
      index_ = element.count;
      return {};
    }
    if constexpr (Source::kBinary) {
      if (element.fixed_size) {
        OCTOLOD_RETURN_IF_ERROR(
            source_.skip_entries(element.count - index_, element.stride, context(element)));
        index_ = element.count;
        return {};
      }
    }
    for (; index_ < element.count; ++index_) {
      OCTOLOD_RETURN_IF_ERROR(source_.begin_entry(context(element)));
      for (const PropertyPlan& p : element.properties) OCTOLOD_RETURN_IF_ERROR(skip_property(p));
      OCTOLOD_RETURN_IF_ERROR(source_.end_entry());
    }
    return {};
  }

  Status skip_property(const PropertyPlan& p) {
    if (!p.property.is_list) return source_.skip_values(p.property.type, 1);
    std::int64_t count = 0;
    const std::uint64_t where = source_.position();
    OCTOLOD_RETURN_IF_ERROR(source_.read_integer(p.property.count_type, count));
    if (count < 0)
      return error_at(where, "negative count " + std::to_string(count) + " for list '" +
                                 p.property.name + "'");
    return source_.skip_values(p.property.type, static_cast<std::uint64_t>(count));
  }

  // ---- vertices ----

  Status decode_vertices(const ElementPlan& element, std::size_t& produced) {
    const std::size_t floats = info_.layout.floats();
    // Small files get small buffers: the count was checked against the file size.
    const std::size_t room = static_cast<std::size_t>(std::min<std::uint64_t>(
        element.count, std::max<std::size_t>(1, batch_bytes_ / (floats * sizeof(float)))));
    if (vertices_.empty()) vertices_.resize(room * floats);
    // the first vertex sets the origin (the generic path), the fast path takes the rest
    if (origin_pending_) OCTOLOD_RETURN_IF_ERROR(decode_vertices_generic(element, 1, produced));
    if constexpr (Source::kBinary) {
      if (element.fixed_size && element.stride <= in_->capacity() / 2)
        OCTOLOD_RETURN_IF_ERROR(decode_vertices_fixed(element, room, produced));
    }
    return decode_vertices_generic(element, room, produced);
  }

  // The generic path: ascii, lists in the vertex element, or an entry the fast path left for a
  // precise error message. Up to `room` vertices in all.
  Status decode_vertices_generic(const ElementPlan& element, std::size_t room, std::size_t& produced) {
    const std::size_t floats = info_.layout.floats();
    for (; produced < room && index_ < element.count; ++produced, ++index_) {
      float* vertex = vertices_.data() + produced * floats;
      OCTOLOD_RETURN_IF_ERROR(source_.begin_entry(context(element)));
      for (const PropertyPlan& p : element.properties) {
        if (p.property.is_list || p.slot == kNoSlot) {
          OCTOLOD_RETURN_IF_ERROR(skip_property(p));
          continue;
        }
        const std::uint64_t where = source_.position();
        double value = 0;
        OCTOLOD_RETURN_IF_ERROR(source_.read_number(p.property.type, value));
        if (p.axis >= 0) {
          double& origin = info_.position_origin[static_cast<std::size_t>(p.axis)];
          if (origin_pending_ && std::isfinite(value)) origin = std::round(value);
          value -= origin;
        }
        auto converted = convert_value(where, "vertex", p, value);
        if (!converted.ok()) return converted.status();
        vertex[p.slot] = converted.value();
      }
      OCTOLOD_RETURN_IF_ERROR(source_.end_entry());
      origin_pending_ = false;
    }
    return {};
  }

  // Binary entries of fixed size decoded straight from the file buffer.
  Status decode_vertices_fixed(const ElementPlan& element, std::size_t room,
                               std::size_t& produced) {
    constexpr bool kSwap = Source::kSwapBytes;
    struct Kept {
      std::size_t offset;
      ScalarType type;
      std::uint32_t slot;
      double divisor;
      double origin;
    };
    std::array<Kept, 16> kept{};  // at most 14 floats per vertex, one property each
    std::size_t kept_count = 0;
    for (const PropertyPlan& p : element.properties)
      if (p.slot != kNoSlot)
        kept[kept_count++] = Kept{p.offset, p.property.type, p.slot, p.divisor,
                                  p.axis >= 0 ? info_.position_origin[static_cast<std::size_t>(p.axis)] : 0.0};
    const std::size_t floats = info_.layout.floats();
    const std::size_t stride = element.stride;
    ply::FileBuffer& in = *in_;
    while (produced < room && index_ < element.count) {
      if (in.available() < stride) {
        OCTOLOD_RETURN_IF_ERROR(in.fill(in.capacity()));
        if (in.available() < stride) return {};  // truncated: the generic path reports it
      }
      const std::size_t n = static_cast<std::size_t>(std::min<std::uint64_t>(
          {in.available() / stride, room - produced, element.count - index_}));
      const char* entry = in.data();
      float* vertex = vertices_.data() + produced * floats;
      std::size_t good = 0;
      for (; good < n; ++good, entry += stride, vertex += floats) {
        bool in_range = true;  // NaN fails the comparison too
        for (std::size_t k = 0; k < kept_count; ++k) {
          const Kept& p = kept[k];
          float value;
          if (p.type == ScalarType::float32 && p.origin == 0.0) {
            value = std::bit_cast<float>(ply::load<std::uint32_t, kSwap>(entry + p.offset));
          } else {
            const double wide = ply::load_as_double<kSwap>(entry + p.offset, p.type) - p.origin;
            value = static_cast<float>(p.divisor != 0.0 ? wide / p.divisor : wide);
          }
          vertex[p.slot] = value;
          in_range &= std::abs(value) <= kMaxVertexValue;
        }
        if (!in_range) break;
      }
      in.consume(good * stride);
      produced += good;
      index_ += good;
      if (good < n) return {};  // a value out of range: the generic path reports it
    }
    return {};
  }

  // `value`, read at `where` for property `p` of entry index_ of the element `entry` names
  // ("vertex"), as the float a batch holds: divided by p.divisor, finite, within
  // ±kMaxVertexValue.
  Result<float> convert_value(std::uint64_t where, const char* entry, const PropertyPlan& p,
                              double value) const {
    const float converted = static_cast<float>(p.divisor != 0.0 ? value / p.divisor : value);
    if (!std::isfinite(converted))
      return error_at(where, std::string(entry) + " " + std::to_string(index_) + " has a non-finite " +
                                 p.property.name + " (" + (std::isnan(converted) ? "NaN" : "Inf") +
                                 (std::isfinite(value) ? " after conversion to float" : "") + ")");
    if (std::abs(converted) > kMaxVertexValue)
      return error_at(where, std::string(entry) + " " + std::to_string(index_) + " has a " +
                                 p.property.name + " of " + beyond_max_vertex_value(converted));
    return converted;
  }

  // ---- faces ----

  Status decode_faces(const ElementPlan& element, std::size_t& produced) {
    const std::size_t room = batch_bytes_ / (3 * sizeof(std::uint32_t));
    if (triangles_.empty()) triangles_.resize(room * 3);
    if (info_.corners.any()) return decode_faces_with_corners(element, room, produced);
    if constexpr (Source::kBinary) {
      const PropertyPlan& p = element.properties.front();
      if (!face_.started && element.properties.size() == 1 &&
          ply::size_of(p.property.count_type) == 1 && ply::size_of(p.property.type) == 4) {
        const bool done_or_full = decode_faces_fast(element, room, produced);
        if (done_or_full) return {};
      }
    }
    return decode_faces_generic(element, room, produced);
  }

  // The common binary layout: `list uchar int vertex_indices` alone in the face element.
  // Returns true when it stopped because the element or the batch is complete; false leaves
  // the current entry (truncated or invalid) to the generic path, which reports the error.
  bool decode_faces_fast(const ElementPlan& element, std::size_t room, std::size_t& produced) {
    constexpr bool kSwap = Source::kSwapBytes;
    constexpr std::size_t kLargestEntry = 1 + 255 * 4;
    const PropertyPlan& p = element.properties.front();
    const bool signed_count = p.property.count_type == ScalarType::int8;
    // Negative int32 indices read as uint32 are >= 2^31, so this one comparison covers both.
    const std::uint64_t limit =
        p.property.type == ScalarType::int32
            ? std::min<std::uint64_t>(info_.vertex_count, std::uint64_t{1} << 31)
            : info_.vertex_count;
    ply::FileBuffer& in = *in_;
    std::uint32_t* out = triangles_.data();
    while (index_ < element.count) {
      if (in.available() < kLargestEntry && !in.exhausted()) {
        if (!in.fill(in.capacity()).ok()) return false;
      }
      if (in.available() == 0) return false;
      const char* entry = in.data();
      const std::int64_t n = signed_count ? static_cast<std::int8_t>(entry[0])
                                          : static_cast<std::uint8_t>(entry[0]);
      if (n < 3) return false;
      const std::size_t bytes = 1 + static_cast<std::size_t>(n) * 4;
      if (in.available() < bytes) return false;
      const std::size_t fan = static_cast<std::size_t>(n) - 2;
      if (room - produced < fan) return true;
      const std::uint32_t v0 = ply::load<std::uint32_t, kSwap>(entry + 1);
      std::uint32_t previous = ply::load<std::uint32_t, kSwap>(entry + 5);
      bool valid = v0 < limit && previous < limit;
      std::uint32_t* tri = out + produced * 3;
      for (std::int64_t k = 2; k < n; ++k, tri += 3) {
        const std::uint32_t v = ply::load<std::uint32_t, kSwap>(entry + 1 + 4 * k);
        valid &= v < limit;
        tri[0] = v0;
        tri[1] = previous;
        tri[2] = v;
        previous = v;
      }
      if (!valid) return false;
      in.consume(bytes);
      produced += fan;
      ++index_;
      if (produced == room) return true;
    }
    return true;
  }

  Status decode_faces_generic(const ElementPlan& element, std::size_t room,
                              std::size_t& produced) {
    std::uint32_t* out = triangles_.data();
    while (index_ < element.count) {
      if (!face_.started) {
        OCTOLOD_RETURN_IF_ERROR(source_.begin_entry(context(element)));
        face_.started = true;
      }
      for (; face_.property < element.properties.size(); ++face_.property) {
        const PropertyPlan& p = element.properties[face_.property];
        if (!p.is_index_list) {
          OCTOLOD_RETURN_IF_ERROR(skip_property(p));
          continue;
        }
        if (!face_.in_list) {
          const std::uint64_t where = source_.position();
          std::int64_t length = 0;
          OCTOLOD_RETURN_IF_ERROR(source_.read_integer(p.property.count_type, length));
          OCTOLOD_RETURN_IF_ERROR(check_polygon_length(where, length));
          face_.in_list = true;
          face_.length = static_cast<std::uint32_t>(length);
          face_.done = 0;
        }
        while (face_.done < face_.length) {
          if (face_.done >= 2 && produced == room) return {};  // the batch is full
          const std::uint64_t where = source_.position();
          std::int64_t index = 0;
          OCTOLOD_RETURN_IF_ERROR(source_.read_integer(p.property.type, index));
          OCTOLOD_RETURN_IF_ERROR(check_vertex_index(where, index));
          const auto v = static_cast<std::uint32_t>(index);
          if (face_.done == 0) {
            face_.first = v;
          } else if (face_.done >= 2) {
            std::uint32_t* tri = out + produced * 3;
            tri[0] = face_.first;
            tri[1] = face_.previous;
            tri[2] = v;
            ++produced;
          }
          face_.previous = v;
          ++face_.done;
        }
        face_.in_list = false;
      }
      OCTOLOD_RETURN_IF_ERROR(source_.end_entry());
      face_ = FaceProgress{};
      ++index_;
    }
    return {};
  }

  // Faces that give their corners attributes (info_.corners): each entry is read whole (its
  // indices, texcoord list and colour, in any order), then fanned out; a fan larger than the
  // batch's room continues in the next batch. index_ moves on once its whole fan is out.
  Status decode_faces_with_corners(const ElementPlan& element, std::size_t room, std::size_t& produced) {
    const std::size_t floats = info_.corners.floats();
    if (corner_values_.empty()) corner_values_.resize(room * 3 * floats);
    for (;;) {
      // the polygon read last: triangles (p0, p[k], p[k + 1]) as decode_faces_generic fans them
      for (; polygon_fanned_ + 2 < polygon_.size() && produced < room; ++polygon_fanned_, ++produced) {
        const std::size_t k = polygon_fanned_ + 1;
        const std::size_t corners[3] = {0, k, k + 1};
        for (std::size_t c = 0; c < 3; ++c) {
          triangles_[produced * 3 + c] = polygon_[corners[c]];
          float* values = corner_values_.data() + (produced * 3 + c) * floats;
          if (info_.corners.color) values = std::copy(polygon_color_.begin(), polygon_color_.end(), values);
          if (info_.corners.uv) {
            values[0] = polygon_uvs_[2 * corners[c]];
            values[1] = polygon_uvs_[2 * corners[c] + 1];
          }
        }
      }
      if (polygon_fanned_ + 2 < polygon_.size()) return {};  // the batch is full
      if (!polygon_.empty()) {
        polygon_.clear();
        ++index_;
      }
      if (index_ == element.count || produced == room) return {};
      OCTOLOD_RETURN_IF_ERROR(read_polygon_with_corners(element));
      polygon_fanned_ = 0;
    }
  }

  // One face entry into polygon_ (vertex indices, checked), polygon_uvs_ (u, v per corner) and
  // polygon_color_.
  Status read_polygon_with_corners(const ElementPlan& element) {
    OCTOLOD_RETURN_IF_ERROR(source_.begin_entry(context(element)));
    polygon_.clear();
    polygon_uvs_.clear();
    std::uint64_t uvs_where = source_.position();
    for (const PropertyPlan& p : element.properties) {
      const std::uint64_t where = source_.position();
      if (!p.property.is_list && p.slot != kNoSlot) {  // a colour channel
        double value = 0;
        OCTOLOD_RETURN_IF_ERROR(source_.read_number(p.property.type, value));
        auto converted = convert_value(where, "face", p, value);
        if (!converted.ok()) return converted.status();
        polygon_color_[p.slot] = converted.value();
        continue;
      }
      if (!p.is_index_list && !p.is_uv_list) {
        OCTOLOD_RETURN_IF_ERROR(skip_property(p));
        continue;
      }
      std::int64_t length = 0;
      OCTOLOD_RETURN_IF_ERROR(source_.read_integer(p.property.count_type, length));
      if (p.is_index_list) {
        OCTOLOD_RETURN_IF_ERROR(check_polygon_length(where, length));
        for (std::int64_t i = 0; i < length; ++i) {
          const std::uint64_t at = source_.position();
          std::int64_t index = 0;
          OCTOLOD_RETURN_IF_ERROR(source_.read_integer(p.property.type, index));
          OCTOLOD_RETURN_IF_ERROR(check_vertex_index(at, index));
          polygon_.push_back(static_cast<std::uint32_t>(index));
        }
        continue;
      }
      uvs_where = where;
      if (length < 0 || static_cast<std::uint64_t>(length) > 2 * kMaxPolygonVertices)
        return error_at(where, "face " + std::to_string(index_) + " has " + std::to_string(length) +
                                   " texture coordinates (a polygon has 3 to " +
                                   std::to_string(kMaxPolygonVertices) + " corners, u and v each)");
      for (std::int64_t i = 0; i < length; ++i) {
        const std::uint64_t at = source_.position();
        double value = 0;
        OCTOLOD_RETURN_IF_ERROR(source_.read_number(p.property.type, value));
        const auto converted = static_cast<float>(value);
        if (!std::isfinite(converted) || std::abs(converted) > kMaxVertexValue)
          return error_at(at, "face " + std::to_string(index_) + " has a texture coordinate of " +
                                  (std::isfinite(converted) ? beyond_max_vertex_value(converted)
                                                            : std::string(std::isnan(converted) ? "NaN" : "Inf")));
        polygon_uvs_.push_back(converted);
      }
    }
    OCTOLOD_RETURN_IF_ERROR(source_.end_entry());
    if (info_.corners.uv && polygon_uvs_.size() != 2 * polygon_.size())
      return error_at(uvs_where, "face " + std::to_string(index_) + " has " +
                                     std::to_string(polygon_uvs_.size()) + " texture coordinates for " +
                                     std::to_string(polygon_.size()) +
                                     " vertices (texcoord holds u and v for every corner)");
    return {};
  }

  // A face's index list length, read at `where`: a polygon.
  Status check_polygon_length(std::uint64_t where, std::int64_t length) const {
    if (length < 3 || static_cast<std::uint64_t>(length) > kMaxPolygonVertices)
      return error_at(where, "face " + std::to_string(index_) + " has " + std::to_string(length) +
                                 " vertices (a polygon needs 3 to " + std::to_string(kMaxPolygonVertices) + ")");
    return {};
  }

  // An index read from a face's list: a vertex of the file.
  Status check_vertex_index(std::uint64_t where, std::int64_t index) const {
    if (index < 0)
      return error_at(where, "face " + std::to_string(index_) + " has a negative vertex index " +
                                 std::to_string(index));
    if (static_cast<std::uint64_t>(index) >= info_.vertex_count)
      return error_at(where, "face " + std::to_string(index_) + " has vertex index " +
                                 std::to_string(index) + ", out of range (the file has " +
                                 std::to_string(info_.vertex_count) + " vertices)");
    return {};
  }

  std::unique_ptr<ply::FileBuffer> in_;
  Source source_;
  Plan plan_;
  std::size_t batch_bytes_;
  std::vector<float> vertices_;
  std::vector<std::uint32_t> triangles_;
  std::vector<float> corner_values_;       // info_.corners: the values of each corner of triangles_
  std::vector<std::uint32_t> polygon_;     // decode_faces_with_corners: the face read last
  std::vector<float> polygon_uvs_;         // its texcoord list
  std::array<float, 3> polygon_color_{};   // its colour
  std::size_t polygon_fanned_ = 0;         // its fan's triangles already in a batch
  std::size_t element_ = 0;   // current element
  std::uint64_t index_ = 0;   // next entry of the current element
  FaceProgress face_;
  std::uint64_t vertices_emitted_ = 0;
  std::uint64_t triangles_emitted_ = 0;
  bool trailing_checked_ = false;
  bool origin_pending_ = false;  // the first vertex sets info_.position_origin
  Status failure_;
};

// read_ply's wedges: one vertex per distinct (file vertex, corner values) of the corners, in
// first-use order, carrying those values.
void weld_corners(PlyMesh& mesh, std::span<const float> corner_values) {
  const VertexLayout layout = mesh.info.layout;
  const std::size_t floats = layout.floats();
  const std::size_t corner_floats = mesh.info.corners.floats();
  const std::size_t first = mesh.info.corners.first_offset(layout);
  struct Wedge {
    std::uint32_t vertex = 0;
    std::array<std::uint32_t, 5> values{};  // bit patterns, unused ones zero
    bool operator==(const Wedge&) const = default;
  };
  struct WedgeHash {
    std::size_t operator()(const Wedge& w) const {
      std::uint64_t h = w.vertex;
      for (std::uint32_t value : w.values) h = (h ^ value) * 0x100000001B3u;
      return std::hash<std::uint64_t>{}(h);
    }
  };
  std::unordered_map<Wedge, std::uint32_t, WedgeHash> wedges;
  std::vector<float> vertices;
  for (std::size_t corner = 0; corner < mesh.triangles.size(); ++corner) {
    const float* values = corner_values.data() + corner * corner_floats;
    Wedge key{.vertex = mesh.triangles[corner]};
    for (std::size_t i = 0; i < corner_floats; ++i) key.values[i] = std::bit_cast<std::uint32_t>(values[i]);
    const auto [it, added] = wedges.try_emplace(key, static_cast<std::uint32_t>(wedges.size()));
    if (added) {
      const float* source = mesh.vertices.data() + std::size_t{key.vertex} * floats;
      vertices.insert(vertices.end(), source, source + floats);
      std::copy(values, values + corner_floats, vertices.end() - static_cast<std::ptrdiff_t>(floats - first));
    }
    mesh.triangles[corner] = it->second;
  }
  mesh.vertices = std::move(vertices);
}

}  // namespace

Result<std::unique_ptr<PlyReader>> PlyReader::open(const std::filesystem::path& path,
                                                   const PlyReadOptions& options) {
  auto in = std::make_unique<ply::FileBuffer>();
  OCTOLOD_RETURN_IF_ERROR(in->open(path));
  Result<ply::Header> header = ply::parse_header(*in);
  if (!header.ok()) return header.status();
  Result<Plan> plan = build_plan(header.value(), *in);
  if (!plan.ok()) return plan.status();

  ply::FileBuffer& buffer = *in;
  std::unique_ptr<PlyReader> reader;
  switch (header->format) {
    case PlyFormat::ascii:
      reader = std::make_unique<StreamReader<ply::AsciiSource>>(
          std::move(in), ply::AsciiSource(buffer, header->lines + 1), std::move(plan.value()), options);
      break;
    case PlyFormat::binary_little_endian:
    case PlyFormat::binary_big_endian:
      if (ply::native_format_is(header->format)) {
        reader = std::make_unique<StreamReader<ply::BinarySource<false>>>(
            std::move(in), ply::BinarySource<false>(buffer), std::move(plan.value()), options);
      } else {
        reader = std::make_unique<StreamReader<ply::BinarySource<true>>>(
            std::move(in), ply::BinarySource<true>(buffer), std::move(plan.value()), options);
      }
      break;
  }
  return reader;
}

Result<PlyMesh> read_ply(const std::filesystem::path& path, const PlyReadOptions& options) {
  Result<std::unique_ptr<PlyReader>> opened = PlyReader::open(path, options);
  if (!opened.ok()) return opened.status();
  PlyReader& reader = *opened.value();
  PlyMesh mesh;
  // The counts were checked against the file size by open(), so reserving them is safe.
  mesh.vertices.reserve(reader.info().vertex_count * reader.info().layout.floats());
  mesh.triangles.reserve(reader.info().face_count * 3);
  std::vector<float> corner_values;
  for (;;) {
    Result<PlyBatch> batch = reader.next();
    if (!batch.ok()) return batch.status();
    if (batch->kind == PlyBatch::Kind::end) break;
    if (batch->kind == PlyBatch::Kind::vertices) {
      mesh.vertices.insert(mesh.vertices.end(), batch->vertices.begin(), batch->vertices.end());
    } else {
      mesh.triangles.insert(mesh.triangles.end(), batch->triangles.begin(), batch->triangles.end());
      corner_values.insert(corner_values.end(), batch->corner_values.begin(), batch->corner_values.end());
    }
  }
  mesh.info = reader.info();  // with the origin the first vertex set
  if (mesh.info.corners.any()) weld_corners(mesh, corner_values);
  return mesh;
}

}  // namespace octolod
