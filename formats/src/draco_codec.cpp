// Draco (google/draco 1.5) encoding and decoding of node meshes for KHR_draco_mesh_compression:
// Edgebreaker connectivity, quantized attributes, positions on a grid shared by the whole file.
#include "draco_codec.h"

#include <draco/compression/decode.h>
#include <draco/compression/encode.h>
#include <draco/core/decoder_buffer.h>
#include <draco/core/encoder_buffer.h>
#include <draco/mesh/mesh.h>

#include <algorithm>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>

namespace octolod::detail {
namespace {

// Adds one float attribute with `components` floats per point, read from the interleaved
// vertices at float `offset`; returns its unique id.
int add_attribute(draco::Mesh& out, const NodeMesh& mesh, draco::GeometryAttribute::Type type,
                  std::uint32_t offset, std::uint8_t components) {
  draco::GeometryAttribute attribute;
  attribute.Init(type, nullptr, components, draco::DT_FLOAT32, false,
                 static_cast<std::int64_t>(sizeof(float) * components), 0);
  const auto count = static_cast<std::uint32_t>(mesh.vertex_count());
  const int id = out.AddAttribute(attribute, true, count);
  draco::PointAttribute* added = out.attribute(id);
  const std::uint32_t stride = mesh.layout.floats();
  for (std::uint32_t v = 0; v < count; ++v)
    added->SetAttributeValue(draco::AttributeValueIndex(v),
                             mesh.vertices.data() + std::size_t{v} * stride + offset);
  added->set_unique_id(static_cast<std::uint32_t>(id));
  return id;
}

// Reads attribute `id` for every point as `components` floats into the interleaved vertices at
// float `offset`.
Status read_attribute(const draco::Mesh& mesh, int id, std::uint8_t components,
                      std::uint32_t offset, NodeMesh& out, std::string_view name,
                      const char* what) {
  const draco::PointAttribute* attribute =
      mesh.GetAttributeByUniqueId(static_cast<std::uint32_t>(id));
  if (attribute == nullptr)
    return bad_input_error(std::string(name) + ": Draco payload has no attribute " +
                           std::to_string(id) + " (" + what + ")");
  // Colours may carry alpha (4 components); it is dropped. Anything else must match exactly.
  const bool alpha_ok = components == 3 && attribute->num_components() == 4 &&
                        attribute->attribute_type() == draco::GeometryAttribute::COLOR;
  if (attribute->num_components() != components && !alpha_ok)
    return bad_input_error(std::string(name) + ": Draco " + what + " attribute has " +
                           std::to_string(attribute->num_components()) + " components, expected " +
                           std::to_string(components));
  const std::uint32_t stride = out.layout.floats();
  float value[4];
  for (std::uint32_t p = 0; p < mesh.num_points(); ++p) {
    const draco::AttributeValueIndex index = attribute->mapped_index(draco::PointIndex(p));
    if (index.value() >= attribute->size() ||
        !attribute->ConvertValue<float>(
            index, static_cast<std::int8_t>(attribute->num_components()), value))
      return bad_input_error(std::string(name) + ": Draco " + what +
                             " attribute has no value for point " + std::to_string(p));
    std::copy(value, value + components, out.vertices.data() + std::size_t{p} * stride + offset);
  }
  return {};
}

}  // namespace

DracoPositionGrid DracoPositionGrid::enclosing(const Bounds& bounds) {
  DracoPositionGrid grid;
  if (bounds.empty()) return grid;
  float extent = 0;
  for (std::size_t i = 0; i < 3; ++i) extent = std::max(extent, bounds.max[i] - bounds.min[i]);
  grid.origin = bounds.min;
  // Draco maps origin + range to the top quantization level; a zero range (one point) would
  // divide by zero.
  grid.range = extent > 0 ? extent : 1.0f;
  return grid;
}

Result<DracoPayload> draco_encode(const NodeMesh& mesh, const DracoOptions& options,
                                  const DracoPositionGrid& grid, std::string_view name) {
  draco::Mesh out;
  out.set_num_points(static_cast<std::uint32_t>(mesh.vertex_count()));
  out.SetNumFaces(mesh.triangle_count());
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    draco::Mesh::Face face;
    for (std::size_t k = 0; k < 3; ++k) face[k] = draco::PointIndex(mesh.indices[3 * t + k]);
    out.SetFace(draco::FaceIndex(static_cast<std::uint32_t>(t)), face);
  }

  DracoPayload payload;
  const VertexLayout& layout = mesh.layout;
  payload.ids.position = add_attribute(out, mesh, draco::GeometryAttribute::POSITION,
                                       VertexLayout::position_offset(), 3);
  if (layout.normal)
    payload.ids.normal = add_attribute(out, mesh, draco::GeometryAttribute::NORMAL,
                                       VertexLayout::normal_offset(), 3);
  if (layout.color)
    payload.ids.color =
        add_attribute(out, mesh, draco::GeometryAttribute::COLOR, layout.color_offset(), 3);
  if (layout.uv)
    payload.ids.uv =
        add_attribute(out, mesh, draco::GeometryAttribute::TEX_COORD, layout.uv_offset(), 2);

  draco::Encoder encoder;
  const int speed = 10 - options.compression_level;
  encoder.SetSpeedOptions(speed, speed);
  encoder.SetEncodingMethod(draco::MESH_EDGEBREAKER_ENCODING);
  encoder.SetAttributeExplicitQuantization(
      draco::GeometryAttribute::POSITION, options.position_bits, 3, grid.origin.data(), grid.range);
  encoder.SetAttributeQuantization(draco::GeometryAttribute::NORMAL, options.normal_bits);
  encoder.SetAttributeQuantization(draco::GeometryAttribute::COLOR, options.color_bits);
  encoder.SetAttributeQuantization(draco::GeometryAttribute::TEX_COORD, options.uv_bits);

  draco::EncoderBuffer buffer;
  const draco::Status encoded = encoder.EncodeMeshToBuffer(out, &buffer);
  if (!encoded.ok())
    return bad_input_error(std::string(name) +
                           ": Draco encoding failed: " + encoded.error_msg_string());
  const auto* data = reinterpret_cast<const std::byte*>(buffer.data());
  payload.bytes.assign(data, data + buffer.size());
  return payload;
}

Result<NodeMesh> draco_decode(std::span<const std::byte> bytes, const DracoAttributeIds& ids,
                              std::string_view name) {
  if (ids.position < 0)
    return bad_input_error(std::string(name) + ": Draco primitive without POSITION");
  draco::DecoderBuffer buffer;
  buffer.Init(reinterpret_cast<const char*>(bytes.data()), bytes.size());
  draco::Decoder decoder;
  auto decoded = decoder.DecodeMeshFromBuffer(&buffer);
  if (!decoded.ok())
    return bad_input_error(std::string(name) +
                           ": invalid Draco payload: " + decoded.status().error_msg_string());
  const draco::Mesh& mesh = *decoded.value();

  NodeMesh out;
  out.layout = VertexLayout{ids.normal >= 0, ids.color >= 0, ids.uv >= 0};
  const std::uint32_t points = mesh.num_points();
  if (points > static_cast<std::uint32_t>(std::numeric_limits<std::int32_t>::max()))
    return bad_input_error(std::string(name) + ": Draco payload with too many points");
  out.vertices.resize(std::size_t{points} * out.layout.floats());
  OCTOLOD_RETURN_IF_ERROR(read_attribute(mesh, ids.position, 3, VertexLayout::position_offset(),
                                         out, name, "POSITION"));
  if (ids.normal >= 0)
    OCTOLOD_RETURN_IF_ERROR(
        read_attribute(mesh, ids.normal, 3, VertexLayout::normal_offset(), out, name, "NORMAL"));
  if (ids.color >= 0)
    OCTOLOD_RETURN_IF_ERROR(
        read_attribute(mesh, ids.color, 3, out.layout.color_offset(), out, name, "COLOR_0"));
  if (ids.uv >= 0)
    OCTOLOD_RETURN_IF_ERROR(
        read_attribute(mesh, ids.uv, 2, out.layout.uv_offset(), out, name, "TEXCOORD_0"));

  out.indices.reserve(std::size_t{mesh.num_faces()} * 3);
  for (std::uint32_t f = 0; f < mesh.num_faces(); ++f) {
    const draco::Mesh::Face& face = mesh.face(draco::FaceIndex(f));
    for (const draco::PointIndex& p : face) {
      if (p.value() >= points)
        return bad_input_error(std::string(name) + ": Draco face " + std::to_string(f) +
                               " references point " + std::to_string(p.value()) + " of " +
                               std::to_string(points));
      out.indices.push_back(p.value());
    }
  }
  return out;
}

}  // namespace octolod::detail
