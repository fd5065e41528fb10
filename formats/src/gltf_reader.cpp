// glTF 2.0 / GLB reader for triangle meshes (Khronos glTF 2.0 specification, sections 4.4
// "Buffers", 5.1 "Accessors", 4.4.3 "GLB file format"; KHR_draco_mesh_compression).
//
// Parsed here with nlohmann::json rather than tinygltf's loader: Debian's libtinygltf is built
// without Draco and rejects the bufferView-less index accessors of Draco primitives, and its
// loader indexes buffers and views unchecked on malformed input. Every count, offset and index
// below is range-checked before use, so any byte string yields a mesh or a bad_input Status.
#include <algorithm>
#include <array>
#include <cstdio>
#include <cstring>
#include <deque>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "byte_io.h"
#include "draco_codec.h"
#include "gltf_uv.h"
#include "octolod/formats/gltf.h"
#include "octolod/formats/input_file.h"

namespace octolod {
namespace {

using nlohmann::json;

constexpr std::uint32_t kGlbMagic = 0x46546C67;   // "glTF"
constexpr std::uint32_t kChunkJson = 0x4E4F534A;  // "JSON"
constexpr std::uint32_t kChunkBin = 0x004E4942;   // "BIN\0"
constexpr int kFloat = 5126, kUnsignedByte = 5121, kUnsignedShort = 5123, kUnsignedInt = 5125;
constexpr const char* kDracoExtension = "KHR_draco_mesh_compression";

std::size_t component_bytes(int type) {
  switch (type) {
    case kUnsignedByte: return 1;
    case kUnsignedShort: return 2;
    case kFloat:
    case kUnsignedInt: return 4;
    default: return 0;
  }
}

std::size_t type_components(const std::string& type) {
  if (type == "SCALAR") return 1;
  if (type == "VEC2") return 2;
  if (type == "VEC3") return 3;
  if (type == "VEC4") return 4;
  return 0;
}

// Standard base64 (RFC 4648) with optional '=' padding; nullopt on any other character.
std::optional<std::vector<std::byte>> decode_base64(std::string_view text) {
  std::array<int, 256> value;
  value.fill(-1);
  const char* alphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  for (int i = 0; i < 64; ++i) value[static_cast<unsigned char>(alphabet[i])] = i;
  while (!text.empty() && text.back() == '=') text.remove_suffix(1);
  std::vector<std::byte> out;
  out.reserve(text.size() * 3 / 4);
  std::uint32_t bits = 0;
  int pending = 0;
  for (char c : text) {
    const int v = value[static_cast<unsigned char>(c)];
    if (v < 0) return std::nullopt;
    bits = (bits << 6) | static_cast<std::uint32_t>(v);
    pending += 6;
    if (pending >= 8) {
      pending -= 8;
      out.push_back(static_cast<std::byte>((bits >> pending) & 0xFFu));
    }
  }
  return out;
}

// Copies `mesh` into `layout` (a subset of its own), dropping the other attributes.
NodeMesh restrict_layout(const NodeMesh& mesh, VertexLayout layout) {
  if (mesh.layout == layout) return mesh;
  NodeMesh out;
  out.layout = layout;
  out.indices = mesh.indices;
  const std::size_t count = mesh.vertex_count();
  out.vertices.reserve(count * layout.floats());
  for (std::size_t v = 0; v < count; ++v) {
    const float* src = mesh.vertices.data() + v * mesh.layout.floats();
    auto copy = [&](std::uint32_t offset, std::uint32_t n) {
      out.vertices.insert(out.vertices.end(), src + offset, src + offset + n);
    };
    copy(VertexLayout::position_offset(), 3);
    if (layout.normal) copy(VertexLayout::normal_offset(), 3);
    if (layout.color) copy(mesh.layout.color_offset(), 3);
    if (layout.uv) copy(mesh.layout.uv_offset(), 2);
  }
  return out;
}

// What an attribute accessor may hold: the glTF 2.0 core types for each attribute (3.7.2.1).
struct AttributeSpec {
  const char* semantic;
  std::uint32_t components;    // floats written per vertex
  bool allow_vec4;             // colours: alpha is read and dropped
  bool allow_normalized_ints;  // unsigned byte/short, normalized to 0..1
};

class GltfDecoder {
 public:
  GltfDecoder(std::string_view name, const std::filesystem::path* base_dir)
      : name_(name), base_dir_(base_dir) {}

  Result<std::vector<NodeMesh>> decode(std::span<const std::byte> bytes) {
    std::span<const std::byte> json_text = bytes;
    if (bytes.size() >= 4 && detail::load_le<std::uint32_t>(bytes, 0) == kGlbMagic)
      OCTOLOD_RETURN_IF_ERROR(split_glb(bytes, json_text));
    OCTOLOD_RETURN_IF_ERROR(parse_json(json_text));
    OCTOLOD_RETURN_IF_ERROR(check_asset());
    OCTOLOD_RETURN_IF_ERROR(load_buffers());

    std::vector<NodeMesh> meshes;
    const json& gltf_meshes = array("meshes");
    for (std::size_t i = 0; i < gltf_meshes.size(); ++i) {
      Result<NodeMesh> mesh = read_mesh(gltf_meshes[i], "mesh " + std::to_string(i));
      if (!mesh.ok()) return mesh.status();
      meshes.push_back(std::move(mesh).value());
      detail::flip_v(meshes.back());  // v up again (gltf_uv.h)
    }
    return meshes;
  }

 private:
  Status fail(const std::string& what) const {
    return bad_input_error(std::string(name_) + ": " + what);
  }
  Status unsupported(const std::string& what) const {
    return unsupported_error(std::string(name_) + ": " + what);
  }

  // --- container -----------------------------------------------------------------------------

  // GLB: 12-byte header (magic, version, length), then chunks (length, type, data); the first
  // chunk is JSON, an optional BIN chunk follows, unknown chunks are skipped.
  Status split_glb(std::span<const std::byte> bytes, std::span<const std::byte>& json_text) {
    if (bytes.size() < 12)
      return fail("truncated GLB header (" + std::to_string(bytes.size()) + " bytes)");
    const auto version = detail::load_le<std::uint32_t>(bytes, 4);
    if (version == 1) return unsupported("GLB version 1 (glTF 1.0); only glTF 2.0 is read");
    if (version != 2) return fail("GLB version " + std::to_string(version) + ", expected 2");
    const auto length = detail::load_le<std::uint32_t>(bytes, 8);
    if (length != bytes.size())
      return fail("GLB header gives a length of " + std::to_string(length) +
                  " bytes, the data has " + std::to_string(bytes.size()) +
                  (length > bytes.size() ? " (truncated)" : ""));
    bool have_json = false;
    for (std::size_t offset = 12; offset < bytes.size();) {
      if (bytes.size() - offset < 8)
        return fail("truncated GLB chunk header at byte " + std::to_string(offset));
      const auto chunk_length = detail::load_le<std::uint32_t>(bytes, offset);
      const auto chunk_type = detail::load_le<std::uint32_t>(bytes, offset + 4);
      if (chunk_length > bytes.size() - offset - 8)
        return fail("GLB chunk at byte " + std::to_string(offset) + " claims " +
                    std::to_string(chunk_length) + " bytes, past the end of the data");
      const std::span<const std::byte> data = bytes.subspan(offset + 8, chunk_length);
      if (!have_json) {
        if (chunk_type != kChunkJson) return fail("the first GLB chunk is not JSON");
        json_text = data;
        have_json = true;
      } else if (chunk_type == kChunkBin && !bin_) {
        bin_ = data;
      }
      offset += 8 + std::size_t{chunk_length};
    }
    if (!have_json) return fail("GLB without a JSON chunk");
    return {};
  }

  Status parse_json(std::span<const std::byte> text) {
    // GLB pads the JSON chunk with spaces; some writers pad with NULs.
    while (!text.empty() && (text.back() == std::byte{0} || text.back() == std::byte{' '}))
      text = text.first(text.size() - 1);
    const auto* begin = reinterpret_cast<const char*>(text.data());
    doc_ = json::parse(begin, begin + text.size(), nullptr, false);
    if (doc_.is_discarded()) return fail("not glTF: the JSON does not parse");
    if (!doc_.is_object()) return fail("not glTF: the JSON is not an object");
    for (const char* key :
         {"meshes", "accessors", "bufferViews", "buffers", "extensionsRequired"}) {
      auto it = doc_.find(key);
      if (it != doc_.end() && !it->is_array())
        return fail(std::string("'") + key + "' is not an array");
    }
    return {};
  }

  Status check_asset() const {
    auto asset = doc_.find("asset");
    if (asset == doc_.end() || !asset->is_object()) return fail("not glTF: no 'asset' object");
    auto version = asset->find("version");
    if (version == asset->end() || !version->is_string()) return fail("asset.version missing");
    const std::string& v = version->get_ref<const std::string&>();
    if (v.rfind("2.", 0) != 0) return unsupported("glTF version " + v + "; only 2.x is read");
    for (const json& required : array("extensionsRequired")) {
      if (!required.is_string()) return fail("extensionsRequired holds a non-string");
      if (required.get_ref<const std::string&>() != kDracoExtension)
        return unsupported("required extension " + required.get<std::string>() +
                           " is not supported");
    }
    return {};
  }

  // --- JSON access -----------------------------------------------------------------------------

  const json& array(const char* key) const {
    static const json empty = json::array();
    auto it = doc_.find(key);
    return it == doc_.end() ? empty : *it;
  }

  // A non-negative integer member; `fallback` when absent (nullopt: the member is required).
  Result<std::uint64_t> count_member(const json& object, const char* key, const std::string& where,
                                     std::optional<std::uint64_t> fallback = std::nullopt) const {
    auto it = object.find(key);
    if (it == object.end()) {
      if (fallback) return *fallback;
      return fail(where + ": '" + key + "' missing");
    }
    if (it->is_number_unsigned()) return it->get<std::uint64_t>();
    return fail(where + ": '" + key + "' is not a non-negative integer");
  }

  // An element of a top-level array, by an index taken from the file.
  Result<const json*> element(const char* array_name, std::uint64_t index,
                              const std::string& where) const {
    const json& items = array(array_name);
    if (index >= items.size())
      return fail(where + ": " + array_name + " index " + std::to_string(index) +
                  " out of range (" + std::to_string(items.size()) + " entries)");
    const json& item = items[static_cast<std::size_t>(index)];
    if (!item.is_object())
      return fail(where + ": " + array_name + "[" + std::to_string(index) + "] is not an object");
    return &item;
  }

  // --- buffers and views -----------------------------------------------------------------------

  Status load_buffers() {
    const json& buffers = array("buffers");
    for (std::size_t i = 0; i < buffers.size(); ++i) {
      const std::string where = "buffer " + std::to_string(i);
      if (!buffers[i].is_object()) return fail(where + " is not an object");
      Result<std::uint64_t> length = count_member(buffers[i], "byteLength", where);
      if (!length.ok()) return length.status();
      std::span<const std::byte> data;
      auto uri = buffers[i].find("uri");
      if (uri == buffers[i].end()) {
        if (i != 0 || !bin_)
          return fail(where + " has no uri and there is no GLB BIN chunk for it");
        data = *bin_;
      } else {
        if (!uri->is_string()) return fail(where + ": uri is not a string");
        Result<std::span<const std::byte>> loaded =
            load_uri(uri->get_ref<const std::string&>(), where);
        if (!loaded.ok()) return loaded.status();
        data = loaded.value();
      }
      if (data.size() < length.value())
        return fail(where + ": byteLength " + std::to_string(length.value()) + " but only " +
                    std::to_string(data.size()) + " bytes of data");
      buffers_.push_back(data.first(static_cast<std::size_t>(length.value())));
    }
    return {};
  }

  Result<std::span<const std::byte>> load_uri(const std::string& uri, const std::string& where) {
    if (uri.rfind("data:", 0) == 0) {
      const std::size_t marker = uri.find(";base64,");
      if (marker == std::string::npos) return unsupported(where + ": data URI is not base64");
      std::optional<std::vector<std::byte>> bytes =
          decode_base64(std::string_view(uri).substr(marker + 8));
      if (!bytes) return fail(where + ": data URI holds invalid base64");
      owned_.push_back(std::move(*bytes));
      return std::span<const std::byte>(owned_.back());
    }
    if (base_dir_ == nullptr || uri.find("://") != std::string::npos)
      return unsupported(where + ": external buffer '" + uri + "' (only self-contained data here)");
    Result<std::vector<std::byte>> bytes = read_input_file(*base_dir_ / uri, "the glTF");
    if (!bytes.ok())
      return Status(bytes.status().code(),
                    std::string(name_) + ": " + where + ": " + bytes.status().message());
    owned_.push_back(std::move(bytes).value());
    return std::span<const std::byte>(owned_.back());
  }

  struct View {
    std::span<const std::byte> bytes;
    std::size_t stride = 0;  // 0: tightly packed
  };

  Result<View> view(std::uint64_t index, const std::string& where) const {
    Result<const json*> object = element("bufferViews", index, where);
    if (!object.ok()) return object.status();
    const std::string at = where + ": bufferView " + std::to_string(index);
    Result<std::uint64_t> buffer = count_member(*object.value(), "buffer", at);
    if (!buffer.ok()) return buffer.status();
    if (buffer.value() >= buffers_.size())
      return fail(at + ": buffer " + std::to_string(buffer.value()) + " out of range");
    Result<std::uint64_t> offset = count_member(*object.value(), "byteOffset", at, 0);
    if (!offset.ok()) return offset.status();
    Result<std::uint64_t> length = count_member(*object.value(), "byteLength", at);
    if (!length.ok()) return length.status();
    Result<std::uint64_t> stride = count_member(*object.value(), "byteStride", at, 0);
    if (!stride.ok()) return stride.status();
    const std::span<const std::byte> data = buffers_[static_cast<std::size_t>(buffer.value())];
    if (length.value() > data.size() || offset.value() > data.size() - length.value())
      return fail(at + ": bytes " + std::to_string(offset.value()) + "+" +
                  std::to_string(length.value()) + " exceed the buffer's " +
                  std::to_string(data.size()));
    if (stride.value() > 252)
      return fail(at + ": byteStride " + std::to_string(stride.value()) + " > 252");
    return View{data.subspan(static_cast<std::size_t>(offset.value()),
                             static_cast<std::size_t>(length.value())),
                static_cast<std::size_t>(stride.value())};
  }

  // --- accessors -------------------------------------------------------------------------------

  struct Accessor {
    int component_type = 0;
    std::size_t components = 0;
    bool normalized = false;
    std::size_t count = 0;
    std::size_t stride = 0;            // bytes between elements
    std::span<const std::byte> bytes;  // from the first element to the end of the view
  };

  Result<Accessor> accessor(std::uint64_t index, const std::string& where) const {
    Result<const json*> object = element("accessors", index, where);
    if (!object.ok()) return object.status();
    const json& a = *object.value();
    const std::string at = where + ": accessor " + std::to_string(index);
    if (a.contains("sparse")) return unsupported(at + " is sparse");
    Accessor out;
    Result<std::uint64_t> type = count_member(a, "componentType", at);
    if (!type.ok()) return type.status();
    out.component_type = type.value() <= 0xFFFF ? static_cast<int>(type.value()) : 0;
    auto type_name = a.find("type");
    if (type_name == a.end() || !type_name->is_string()) return fail(at + ": 'type' missing");
    out.components = type_components(type_name->get_ref<const std::string&>());
    if (out.components == 0) return unsupported(at + ": type " + type_name->get<std::string>());
    const std::size_t element_bytes = component_bytes(out.component_type) * out.components;
    if (element_bytes == 0)
      return unsupported(at + ": componentType " + std::to_string(type.value()));
    auto normalized = a.find("normalized");
    out.normalized = normalized != a.end() && normalized->is_boolean() && normalized->get<bool>();
    Result<std::uint64_t> count = count_member(a, "count", at);
    if (!count.ok()) return count.status();
    Result<std::uint64_t> offset = count_member(a, "byteOffset", at, 0);
    if (!offset.ok()) return offset.status();
    if (!a.contains("bufferView")) return unsupported(at + " has no bufferView (implicit zeros)");
    Result<std::uint64_t> view_index = count_member(a, "bufferView", at);
    if (!view_index.ok()) return view_index.status();
    Result<View> v = view(view_index.value(), at);
    if (!v.ok()) return v.status();
    out.stride = v->stride != 0 ? v->stride : element_bytes;
    if (out.stride < element_bytes)
      return fail(at + ": byteStride " + std::to_string(out.stride) +
                  " is smaller than an element (" + std::to_string(element_bytes) + " bytes)");
    // Elements occupy offset + stride * (count - 1) + element_bytes bytes of the view.
    const std::uint64_t size = v->bytes.size();
    const bool fits = count.value() == 0 ||
                      (offset.value() <= size && count.value() - 1 <= size &&
                       (count.value() - 1) * out.stride + element_bytes <= size - offset.value());
    if (!fits)
      return fail(at + ": " + std::to_string(count.value()) + " elements at byte " +
                  std::to_string(offset.value()) + " overrun its bufferView (" +
                  std::to_string(size) + " bytes)");
    out.count = static_cast<std::size_t>(count.value());
    out.bytes = v->bytes.subspan(static_cast<std::size_t>(offset.value()));
    return out;
  }

  // Component `c` of element `e`, as a float (normalized integers mapped to 0..1).
  static float component(const Accessor& a, std::size_t e, std::size_t c) {
    const std::size_t at = e * a.stride + c * component_bytes(a.component_type);
    switch (a.component_type) {
      case kUnsignedByte:
        return static_cast<float>(std::to_integer<unsigned>(a.bytes[at])) / 255.0f;
      case kUnsignedShort:
        return static_cast<float>(detail::load_le<std::uint16_t>(a.bytes, at)) / 65535.0f;
      default: return detail::load_le<float>(a.bytes, at);
    }
  }

  // Reads attribute accessor `index` into the interleaved vertices of `mesh` at float `offset`.
  Status read_attribute(std::uint64_t index, const AttributeSpec& spec, std::uint32_t offset,
                        NodeMesh& mesh, const std::string& where) const {
    const std::string at = where + " " + spec.semantic;
    Result<Accessor> a = accessor(index, at);
    if (!a.ok()) return a.status();
    const bool float_ok = a->component_type == kFloat;
    const bool int_ok = spec.allow_normalized_ints && a->normalized &&
                        (a->component_type == kUnsignedByte || a->component_type == kUnsignedShort);
    const bool components_ok =
        a->components == spec.components || (spec.allow_vec4 && a->components == 4);
    if (!(float_ok || int_ok) || !components_ok)
      return unsupported(at + ": accessor " + std::to_string(index) + " has componentType " +
                         std::to_string(a->component_type) + " with " +
                         std::to_string(a->components) + " components");
    const std::size_t vertices = mesh.vertex_count();
    if (a->count != vertices)
      return fail(at + ": " + std::to_string(a->count) + " values for " + std::to_string(vertices) +
                  " vertices");
    const std::uint32_t floats = mesh.layout.floats();
    for (std::size_t e = 0; e < vertices; ++e)
      for (std::size_t c = 0; c < spec.components; ++c)
        mesh.vertices[e * floats + offset + c] = component(a.value(), e, c);
    return {};
  }

  Status read_indices(std::uint64_t index, NodeMesh& mesh, const std::string& where) const {
    const std::string at = where + " indices";
    Result<Accessor> a = accessor(index, at);
    if (!a.ok()) return a.status();
    if (a->components != 1 || a->component_type == kFloat)
      return fail(at + ": accessor " + std::to_string(index) + " is not scalar unsigned integers");
    if (a->count % 3 != 0)
      return fail(at + ": " + std::to_string(a->count) + " indices, not whole triangles");
    const std::size_t vertices = mesh.vertex_count();
    mesh.indices.resize(a->count);
    for (std::size_t e = 0; e < a->count; ++e) {
      const std::size_t at_byte = e * a->stride;
      std::uint32_t i = 0;
      switch (a->component_type) {
        case kUnsignedByte: i = std::to_integer<std::uint32_t>(a->bytes[at_byte]); break;
        case kUnsignedShort: i = detail::load_le<std::uint16_t>(a->bytes, at_byte); break;
        default: i = detail::load_le<std::uint32_t>(a->bytes, at_byte); break;
      }
      if (i >= vertices)
        return fail(at + ": index " + std::to_string(e) + " is " + std::to_string(i) +
                    ", but there are " + std::to_string(vertices) + " vertices");
      mesh.indices[e] = i;
    }
    return {};
  }

  // --- meshes ----------------------------------------------------------------------------------

  static constexpr AttributeSpec kPosition{"POSITION", 3, false, false};
  static constexpr AttributeSpec kNormal{"NORMAL", 3, false, false};
  static constexpr AttributeSpec kColor{"COLOR_0", 3, true, true};
  static constexpr AttributeSpec kUv{"TEXCOORD_0", 2, false, true};

  Result<NodeMesh> read_draco_primitive(const json& extension, const std::string& where) const {
    const std::string at = where + " " + kDracoExtension;
    if (!extension.is_object()) return fail(at + " is not an object");
    Result<std::uint64_t> view_index = count_member(extension, "bufferView", at);
    if (!view_index.ok()) return view_index.status();
    Result<View> v = view(view_index.value(), at);
    if (!v.ok()) return v.status();
    auto attributes = extension.find("attributes");
    if (attributes == extension.end() || !attributes->is_object())
      return fail(at + ": 'attributes' missing");
    detail::DracoAttributeIds ids;
    for (auto [semantic, id] : {std::pair{"POSITION", &ids.position},
                                {"NORMAL", &ids.normal},
                                {"COLOR_0", &ids.color},
                                {"TEXCOORD_0", &ids.uv}}) {
      if (!attributes->contains(semantic)) continue;
      Result<std::uint64_t> value = count_member(*attributes, semantic, at + " attributes");
      if (!value.ok()) return value.status();
      if (value.value() > static_cast<std::uint64_t>(std::numeric_limits<int>::max()))
        return fail(at + ": attribute id out of range");
      *id = static_cast<int>(value.value());
    }
    return detail::draco_decode(v->bytes, ids, std::string(name_) + ": " + at);
  }

  Result<NodeMesh> read_primitive(const json& primitive, const std::string& where) const {
    if (!primitive.is_object()) return fail(where + " is not an object");
    Result<std::uint64_t> mode = count_member(primitive, "mode", where, 4);
    if (!mode.ok()) return mode.status();
    if (mode.value() != 4)
      return unsupported(where + ": mode " + std::to_string(mode.value()) + " (only triangles, 4)");
    auto extensions = primitive.find("extensions");
    if (extensions != primitive.end() && extensions->is_object() &&
        extensions->contains(kDracoExtension))
      return read_draco_primitive((*extensions)[kDracoExtension], where);

    auto attributes = primitive.find("attributes");
    if (attributes == primitive.end() || !attributes->is_object())
      return fail(where + ": 'attributes' missing");
    if (!attributes->contains("POSITION")) return fail(where + " has no POSITION");
    NodeMesh mesh;
    mesh.layout = VertexLayout{attributes->contains("NORMAL"), attributes->contains("COLOR_0"),
                               attributes->contains("TEXCOORD_0")};
    Result<std::uint64_t> position = count_member(*attributes, "POSITION", where);
    if (!position.ok()) return position.status();
    Result<Accessor> positions = accessor(position.value(), where + " POSITION");
    if (!positions.ok()) return positions.status();
    mesh.vertices.resize(positions->count * mesh.layout.floats());
    const std::array<std::pair<const AttributeSpec*, std::uint32_t>, 4> reads{{
        {&kPosition, VertexLayout::position_offset()},
        {&kNormal, VertexLayout::normal_offset()},
        {&kColor, mesh.layout.color_offset()},
        {&kUv, mesh.layout.uv_offset()},
    }};
    for (auto [spec, offset] : reads) {
      if (!attributes->contains(spec->semantic)) continue;
      Result<std::uint64_t> index = count_member(*attributes, spec->semantic, where);
      if (!index.ok()) return index.status();
      OCTOLOD_RETURN_IF_ERROR(read_attribute(index.value(), *spec, offset, mesh, where));
    }
    if (primitive.contains("indices")) {
      Result<std::uint64_t> indices = count_member(primitive, "indices", where);
      if (!indices.ok()) return indices.status();
      OCTOLOD_RETURN_IF_ERROR(read_indices(indices.value(), mesh, where));
    } else {
      // Non-indexed triangles: vertices 3t, 3t+1, 3t+2.
      if (mesh.vertex_count() % 3 != 0 ||
          mesh.vertex_count() > std::numeric_limits<std::uint32_t>::max())
        return fail(where + ": " + std::to_string(mesh.vertex_count()) +
                    " unindexed vertices, not whole triangles");
      mesh.indices.resize(mesh.vertex_count());
      for (std::size_t i = 0; i < mesh.indices.size(); ++i)
        mesh.indices[i] = static_cast<std::uint32_t>(i);
    }
    return mesh;
  }

  Result<NodeMesh> read_mesh(const json& mesh, const std::string& where) const {
    if (!mesh.is_object()) return fail(where + " is not an object");
    auto primitives = mesh.find("primitives");
    if (primitives == mesh.end() || !primitives->is_array() || primitives->empty())
      return fail(where + ": no primitives");
    std::vector<NodeMesh> parts;
    for (std::size_t p = 0; p < primitives->size(); ++p) {
      Result<NodeMesh> part =
          read_primitive((*primitives)[p], where + " primitive " + std::to_string(p));
      if (!part.ok()) return part.status();
      parts.push_back(std::move(part).value());
    }
    if (parts.size() == 1) return std::move(parts.front());

    // Several primitives: one mesh with the attributes they all have.
    VertexLayout common = parts.front().layout;
    for (const NodeMesh& part : parts)
      common = VertexLayout::from_mask(common.mask() & part.layout.mask());
    NodeMesh out;
    out.layout = common;
    for (const NodeMesh& part : parts) {
      const NodeMesh restricted = restrict_layout(part, common);
      const std::size_t base = out.vertex_count();
      if (base + restricted.vertex_count() > std::numeric_limits<std::uint32_t>::max())
        return fail(where + ": more than 2^32 vertices");
      out.vertices.insert(out.vertices.end(), restricted.vertices.begin(),
                          restricted.vertices.end());
      for (std::uint32_t i : restricted.indices)
        out.indices.push_back(static_cast<std::uint32_t>(base + i));
    }
    return out;
  }

  std::string_view name_;
  const std::filesystem::path* base_dir_;
  json doc_;
  std::optional<std::span<const std::byte>> bin_;
  std::vector<std::span<const std::byte>> buffers_;
  std::deque<std::vector<std::byte>> owned_;  // decoded data URIs and external files (stable)
};

}  // namespace

Result<std::vector<NodeMesh>> decode_gltf(std::span<const std::byte> bytes, std::string_view name) {
  return GltfDecoder(name, nullptr).decode(bytes);
}

Result<std::vector<NodeMesh>> read_gltf(const std::filesystem::path& path) {
  Result<std::vector<std::byte>> bytes = read_input_file(path, "the glTF");
  if (!bytes.ok()) return bytes.status();
  const std::filesystem::path base_dir = path.parent_path();
  const std::string name = path.string();
  return GltfDecoder(name, &base_dir).decode(bytes.value());
}

}  // namespace octolod
