// glTF 2.0 / GLB writer (Khronos glTF 2.0 specification; KHR_draco_mesh_compression), built on
// tinygltf's serializer. One node + mesh + triangle primitive per NodeMesh; vertex data goes in as
// one interleaved buffer view per mesh (the NodeMesh bytes as they are), or as one Draco payload.
#include <tiny_gltf.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <exception>
#include <initializer_list>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <system_error>

#include "draco_codec.h"
#include "gltf_uv.h"
#include "octolod/formats/input_file.h"
#include "octolod/formats/gltf.h"
#include "octolod/formats/output_file.h"

namespace octolod {
namespace {

constexpr const char* kDracoExtension = "KHR_draco_mesh_compression";
constexpr std::size_t kMaxGltfCount =
    static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max());

Status check_options(std::span<const NodeMesh> meshes, const GltfWriteOptions& options) {
  if (!options.names.empty() && options.names.size() != meshes.size())
    return usage_error("glTF export: " + std::to_string(options.names.size()) + " names for " +
                       std::to_string(meshes.size()) + " meshes (give none or one per mesh)");
  if (!options.draco) return {};
  const DracoOptions& d = options.draco_options;
  for (auto [bits, what] : {std::pair{d.position_bits, "position"},
                            {d.normal_bits, "normal"},
                            {d.color_bits, "color"},
                            {d.uv_bits, "uv"}})
    if (bits < 0 || bits > kMaxDracoBits)
      return usage_error(std::string("glTF export: Draco ") + what + " quantization bits " +
                         std::to_string(bits) + " out of range 0.." + std::to_string(kMaxDracoBits));
  if (d.compression_level < 0 || d.compression_level > 10)
    return usage_error("glTF export: Draco compression level " +
                       std::to_string(d.compression_level) + " out of range 0..10");
  return {};
}

Status check_mesh(const NodeMesh& mesh, const std::string& name) {
  const std::size_t floats = mesh.layout.floats();
  if (mesh.vertices.size() % floats != 0)
    return bad_input_error("glTF export: mesh '" + name + "' has " +
                           std::to_string(mesh.vertices.size()) + " floats, not a multiple of " +
                           std::to_string(floats) + " (" + mesh.layout.describe() + ")");
  if (mesh.indices.size() % 3 != 0)
    return bad_input_error("glTF export: mesh '" + name + "' has " +
                           std::to_string(mesh.indices.size()) + " indices, not whole triangles");
  if (mesh.vertex_count() > kMaxGltfCount || mesh.indices.size() > kMaxGltfCount)
    return bad_input_error("glTF export: mesh '" + name + "' is too large for one primitive");
  const std::size_t vertices = mesh.vertex_count();
  for (std::size_t i = 0; i < mesh.indices.size(); ++i)
    if (mesh.indices[i] >= vertices)
      return bad_input_error("glTF export: mesh '" + name + "' index " + std::to_string(i) +
                             " is " + std::to_string(mesh.indices[i]) + ", but there are " +
                             std::to_string(vertices) + " vertices");
  return {};
}

// Builds the tinygltf model; appends all binary data to model.buffers[0].
class ModelBuilder {
 public:
  // `reserve_bytes`: expected binary data, to grow the buffer once.
  ModelBuilder(const GltfWriteOptions& options, std::size_t reserve_bytes) : options_(options) {
    model_.asset.version = "2.0";
    model_.asset.generator = "octolod";
    model_.buffers.emplace_back();
    model_.buffers[0].data.reserve(reserve_bytes);
    model_.scenes.emplace_back();
    model_.defaultScene = 0;
    if (options.draco) {
      model_.extensionsUsed.push_back(kDracoExtension);
      model_.extensionsRequired.push_back(kDracoExtension);
    }
    if (options.texture) add_material(*options.texture);
  }

  // `mesh` as glTF has it: with v turned down (gltf_uv.h).
  Status add(const NodeMesh& mesh, const std::string& name, const detail::DracoPositionGrid& grid) {
    if (!mesh.layout.uv) return add_node(mesh, name, grid);
    NodeMesh flipped = mesh;
    detail::flip_v(flipped);
    return add_node(flipped, name, grid);
  }

  tinygltf::Model finish() && {
    if (model_.buffers[0].data.empty()) {
      model_.buffers.clear();  // a buffer must not be empty (byteLength >= 1)
    }
    return std::move(model_);
  }

 private:
  Status add_node(const NodeMesh& mesh, const std::string& name, const detail::DracoPositionGrid& grid) {
    tinygltf::Node node;
    node.name = name;
    if (options_.translation != std::array<double, 3>{0.0, 0.0, 0.0})
      node.translation.assign(options_.translation.begin(), options_.translation.end());
    if (mesh.triangle_count() > 0) {
      tinygltf::Mesh gltf_mesh;
      gltf_mesh.name = name;
      tinygltf::Primitive primitive;
      primitive.mode = TINYGLTF_MODE_TRIANGLES;
      if (options_.draco)
        OCTOLOD_RETURN_IF_ERROR(add_draco_primitive(mesh, name, grid, primitive));
      else
        add_plain_primitive(mesh, primitive);
      if (mesh.layout.uv && !model_.materials.empty()) primitive.material = 0;
      gltf_mesh.primitives.push_back(std::move(primitive));
      node.mesh = static_cast<int>(model_.meshes.size());
      model_.meshes.push_back(std::move(gltf_mesh));
    }
    model_.scenes[0].nodes.push_back(static_cast<int>(model_.nodes.size()));
    model_.nodes.push_back(std::move(node));
    return {};
  }

  // Material 0: `texture` as the base colour (repeating, mipmapped), not metallic, as a scan's
  // colour texture is meant.
  void add_material(const GltfTexture& texture) {
    tinygltf::Image image;
    image.name = texture.name;
    image.mimeType = texture.mime_type;
    image.bufferView = add_view(texture.bytes.data(), texture.bytes.size(), 0, 0);
    model_.images.push_back(std::move(image));
    tinygltf::Sampler sampler;
    sampler.magFilter = TINYGLTF_TEXTURE_FILTER_LINEAR;
    sampler.minFilter = TINYGLTF_TEXTURE_FILTER_LINEAR_MIPMAP_LINEAR;
    model_.samplers.push_back(sampler);
    tinygltf::Texture gltf_texture;
    gltf_texture.source = 0;
    gltf_texture.sampler = 0;
    model_.textures.push_back(gltf_texture);
    tinygltf::Material material;
    material.name = texture.name;
    material.pbrMetallicRoughness.baseColorTexture.index = 0;
    material.pbrMetallicRoughness.metallicFactor = 0.0;
    model_.materials.push_back(std::move(material));
  }

  // Appends `bytes` 4-byte aligned (every component type and stride stays aligned); returns the
  // new buffer view's index.
  int add_view(const void* bytes, std::size_t size, std::size_t stride, int target) {
    std::vector<unsigned char>& data = model_.buffers[0].data;
    data.resize((data.size() + 3) & ~std::size_t{3}, 0);
    tinygltf::BufferView view;
    view.buffer = 0;
    view.byteOffset = data.size();
    view.byteLength = size;
    view.byteStride = stride;
    view.target = target;
    const auto* p = static_cast<const unsigned char*>(bytes);
    data.insert(data.end(), p, p + size);
    model_.bufferViews.push_back(view);
    return static_cast<int>(model_.bufferViews.size() - 1);
  }

  int add_accessor(int view, std::size_t byte_offset, int component_type, std::size_t count,
                   int type) {
    tinygltf::Accessor accessor;
    accessor.bufferView = view;
    accessor.byteOffset = byte_offset;
    accessor.componentType = component_type;
    accessor.count = count;
    accessor.type = type;
    model_.accessors.push_back(std::move(accessor));
    return static_cast<int>(model_.accessors.size() - 1);
  }

  // POSITION, NORMAL, COLOR_0, TEXCOORD_0 accessors for `mesh`'s layout, all on `view` (-1 for
  // Draco: the data lives in the payload). POSITION gets the exact min/max of `mesh`.
  void add_vertex_accessors(const NodeMesh& mesh, int view, tinygltf::Primitive& primitive) {
    const VertexLayout& layout = mesh.layout;
    const std::size_t count = mesh.vertex_count();
    auto offset = [&](std::uint32_t floats) { return view >= 0 ? std::size_t{floats} * 4 : 0; };
    const int position = add_accessor(view, offset(VertexLayout::position_offset()),
                                      TINYGLTF_COMPONENT_TYPE_FLOAT, count, TINYGLTF_TYPE_VEC3);
    const Bounds bounds = mesh.bounds();
    model_.accessors[static_cast<std::size_t>(position)].minValues = {bounds.min[0], bounds.min[1],
                                                                      bounds.min[2]};
    model_.accessors[static_cast<std::size_t>(position)].maxValues = {bounds.max[0], bounds.max[1],
                                                                      bounds.max[2]};
    primitive.attributes["POSITION"] = position;
    if (layout.normal)
      primitive.attributes["NORMAL"] =
          add_accessor(view, offset(VertexLayout::normal_offset()), TINYGLTF_COMPONENT_TYPE_FLOAT,
                       count, TINYGLTF_TYPE_VEC3);
    if (layout.color)
      primitive.attributes["COLOR_0"] =
          add_accessor(view, offset(layout.color_offset()), TINYGLTF_COMPONENT_TYPE_FLOAT, count,
                       TINYGLTF_TYPE_VEC3);
    if (layout.uv)
      primitive.attributes["TEXCOORD_0"] =
          add_accessor(view, offset(layout.uv_offset()), TINYGLTF_COMPONENT_TYPE_FLOAT, count,
                       TINYGLTF_TYPE_VEC2);
  }

  // uint16 when the largest index fits below 65535 (the reserved primitive-restart value).
  static bool short_indices(const NodeMesh& mesh) { return mesh.vertex_count() <= 65535; }

  void add_plain_primitive(const NodeMesh& mesh, tinygltf::Primitive& primitive) {
    const int vertex_view = add_view(mesh.vertices.data(), mesh.vertices.size() * sizeof(float),
                                     mesh.layout.bytes(), TINYGLTF_TARGET_ARRAY_BUFFER);
    add_vertex_accessors(mesh, vertex_view, primitive);
    int index_view;
    if (short_indices(mesh)) {
      std::vector<std::uint16_t> narrow(mesh.indices.begin(), mesh.indices.end());
      index_view =
          add_view(narrow.data(), narrow.size() * 2, 0, TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
    } else {
      index_view = add_view(mesh.indices.data(), mesh.indices.size() * 4, 0,
                            TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
    }
    primitive.indices = add_accessor(index_view, 0,
                                     short_indices(mesh) ? TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT
                                                         : TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT,
                                     mesh.indices.size(), TINYGLTF_TYPE_SCALAR);
  }

  // The accessors of a Draco primitive describe the decoded data, so the payload is decoded
  // once here: Edgebreaker may split or drop vertices, and quantization moves positions.
  Status add_draco_primitive(const NodeMesh& mesh, const std::string& name,
                             const detail::DracoPositionGrid& grid,
                             tinygltf::Primitive& primitive) {
    Result<detail::DracoPayload> payload =
        detail::draco_encode(mesh, options_.draco_options, grid, name);
    if (!payload.ok()) return payload.status();
    Result<NodeMesh> decoded = detail::draco_decode(payload->bytes, payload->ids, name);
    if (!decoded.ok()) return decoded.status();

    add_vertex_accessors(decoded.value(), -1, primitive);
    primitive.indices =
        add_accessor(-1, 0,
                     short_indices(decoded.value()) ? TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT
                                                    : TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT,
                     decoded->indices.size(), TINYGLTF_TYPE_SCALAR);
    const int view = add_view(payload->bytes.data(), payload->bytes.size(), 0, 0);

    tinygltf::Value::Object attributes;
    const detail::DracoAttributeIds& ids = payload->ids;
    attributes["POSITION"] = tinygltf::Value(ids.position);
    if (ids.normal >= 0) attributes["NORMAL"] = tinygltf::Value(ids.normal);
    if (ids.color >= 0) attributes["COLOR_0"] = tinygltf::Value(ids.color);
    if (ids.uv >= 0) attributes["TEXCOORD_0"] = tinygltf::Value(ids.uv);
    tinygltf::Value::Object extension;
    extension["bufferView"] = tinygltf::Value(view);
    extension["attributes"] = tinygltf::Value(std::move(attributes));
    primitive.extensions[kDracoExtension] = tinygltf::Value(std::move(extension));
    return {};
  }

  const GltfWriteOptions& options_;
  tinygltf::Model model_;
};

}  // namespace

namespace {

// Validates, builds the model and serializes it into `stream` (nothing is written on a
// validation error).
Status serialize(std::span<const NodeMesh> meshes, const GltfWriteOptions& options,
                 std::ostream& stream) {
  OCTOLOD_RETURN_IF_ERROR(check_options(meshes, options));
  std::vector<std::string> names = options.names;
  for (std::size_t i = names.size(); i < meshes.size(); ++i)
    names.push_back("mesh_" + std::to_string(i));

  Bounds all;
  std::size_t plain_bytes = 0;
  for (std::size_t i = 0; i < meshes.size(); ++i) {
    OCTOLOD_RETURN_IF_ERROR(check_mesh(meshes[i], names[i]));
    if (meshes[i].triangle_count() > 0) all.extend(meshes[i].bounds());
    plain_bytes += (meshes[i].vertices.size() + meshes[i].indices.size()) * 4 + 8;
  }
  const detail::DracoPositionGrid grid = detail::DracoPositionGrid::enclosing(all);

  ModelBuilder builder(options, (options.draco ? 0 : plain_bytes) + (options.texture ? options.texture->bytes.size() + 4 : 0));
  for (std::size_t i = 0; i < meshes.size(); ++i)
    OCTOLOD_RETURN_IF_ERROR(builder.add(meshes[i], names[i], grid));
  const tinygltf::Model model = std::move(builder).finish();

  try {
    tinygltf::TinyGLTF writer;
    if (!writer.WriteGltfSceneToStream(&model, stream, !options.binary, options.binary))
      return io_error("glTF export: tinygltf failed to serialize the model");
  } catch (const std::exception& e) {
    // nlohmann::json (inside tinygltf) throws on names that are not valid UTF-8.
    return bad_input_error(std::string("glTF export: cannot serialize: ") + e.what());
  }
  return {};
}

}  // namespace

Result<GltfTexture> read_gltf_texture(const std::filesystem::path& path) {
  auto bytes = read_input_file(path, "the texture");
  if (!bytes.ok()) return bytes.status();
  const auto starts_with = [&](std::initializer_list<unsigned char> magic) {
    return bytes->size() >= magic.size() &&
           std::equal(magic.begin(), magic.end(), bytes->begin(),
                      [](unsigned char m, std::byte b) { return m == std::to_integer<unsigned char>(b); });
  };
  GltfTexture texture;
  if (starts_with({0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'}))
    texture.mime_type = "image/png";
  else if (starts_with({0xFF, 0xD8, 0xFF}))
    texture.mime_type = "image/jpeg";
  else
    return unsupported_error(path.string() + ": not a PNG or JPEG image, the types glTF 2.0 embeds");
  texture.name = path.filename().string();
  texture.bytes = std::move(bytes).value();
  return texture;
}

Result<std::vector<std::byte>> encode_gltf(std::span<const NodeMesh> meshes,
                                           const GltfWriteOptions& options) {
  std::ostringstream stream;
  OCTOLOD_RETURN_IF_ERROR(serialize(meshes, options, stream));
  const std::string text = std::move(stream).str();
  const auto* p = reinterpret_cast<const std::byte*>(text.data());
  return std::vector<std::byte>(p, p + text.size());
}

// Streams straight into the file: peak memory is the model's buffer plus tinygltf's copy of it.
Status write_gltf(const std::filesystem::path& path, std::span<const NodeMesh> meshes,
                  const GltfWriteOptions& options) {
  OCTOLOD_RETURN_IF_ERROR(check_output_file(path, "the glTF"));
  std::filesystem::path tmp = path;
  tmp += ".tmp-" + std::to_string(::getpid());
  std::ofstream file(tmp, std::ios::binary | std::ios::trunc);
  if (!file)
    return io_error(path.string() + ": cannot create " + tmp.string() + ": " +
                    std::strerror(errno));
  Status status = serialize(meshes, options, file);
  file.close();
  if (status.ok() && file.fail())
    status = io_error(path.string() + ": write failed: " + std::strerror(errno));
  std::error_code ec;
  if (status.ok()) std::filesystem::rename(tmp, path, ec);
  if (ec) status = io_error(path.string() + ": rename failed: " + ec.message());
  if (!status.ok()) {
    std::error_code ignored;
    std::filesystem::remove(tmp, ignored);
  }
  return status;
}

}  // namespace octolod
