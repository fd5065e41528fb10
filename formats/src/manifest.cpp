// manifest.json reading/writing and validation; the schema is documented in docs/formats.md.
#include "octolod/formats/manifest.h"

#include <array>
#include <cassert>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <functional>
#include <limits>
#include <string_view>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include "json_reader.h"
#include "octolod/formats/input_file.h"
#include "manifest_sax.h"

namespace octolod {
namespace {

using nlohmann::json;

// `f` as the double of the shortest decimal that reads back as `f` through a double (as every
// reader of a manifest parses numbers, refusing doubles beyond the float range): at most 9
// significant digits in the text instead of the 17 the double of `f` itself takes. `f` itself
// when the decimal would not read back as it (FLT_MAX's, 3.4028235e38, is above FLT_MAX).
double shortest_float(float f) {
  char text[32];
  const auto written = std::to_chars(text, text + sizeof text, f);
  double d = 0;
  const auto read = std::from_chars(text, written.ptr, d);
  const bool reads_back = read.ec == std::errc{} && static_cast<float>(d) == f &&
                          std::abs(d) <= std::numeric_limits<float>::max();
  return reads_back ? d : f;
}

json bounds_to_json(const Bounds& b) {
  const auto corner = [](const std::array<float, 3>& c) {
    return std::array<double, 3>{shortest_float(c[0]), shortest_float(c[1]), shortest_float(c[2])};
  };
  return json{{"min", corner(b.min)}, {"max", corner(b.max)}};
}

// j[key] as an integer of type T; json::exception when it is missing, not an integer or out of
// T's range.
template <class T>
T integer_at(const json& j, const char* key) {
  const json& v = j.at(key);
  T out{};
  const bool is_unsigned = v.is_number_unsigned(), is_signed = v.is_number_integer() && !is_unsigned;
  if (!integer_in_range(is_signed ? v.get<std::int64_t>() : 0, is_unsigned ? v.get<std::uint64_t>() : 0, is_signed,
                        is_unsigned, out))
    throw json::type_error::create(302, std::string("\"") + key + "\" is not an integer in range", &v);
  return out;
}

// Missing keys, wrong types and numbers beyond the float range throw json::exception.
Bounds bounds_from_json(const json& j) {
  const auto corner = [&](const char* key) {
    const auto d = j.at(key).get<std::array<double, 3>>();
    std::array<float, 3> f;
    for (std::size_t i = 0; i < 3; ++i) {
      if (!within_float_range(d[i]))
        throw json::out_of_range::create(406, std::string("\"") + key + "\" holds a number beyond the float range", &j);
      f[i] = static_cast<float>(d[i]);
    }
    return f;
  };
  Bounds b;
  b.min = corner("min");
  b.max = corner("max");
  return b;
}

json layout_to_json(const VertexLayout& layout) {
  return json{{"normal", layout.normal}, {"color", layout.color}, {"uv", layout.uv},
              {"floats_per_vertex", layout.floats()}};
}

Status invalid(std::string_view name, const std::string& what) {
  return bad_input_error(std::string(name) + ": invalid manifest: " + what);
}

bool safe_relative(const std::string& p) {
  if (p.empty() || p.front() == '/') return false;
  std::size_t start = 0;
  while (start <= p.size()) {
    std::size_t end = p.find('/', start);
    if (end == std::string::npos) end = p.size();
    std::string part = p.substr(start, end - start);
    if (part.empty() || part == "..") return false;
    start = end + 1;
  }
  return true;
}

}  // namespace

Status validate_manifest(const Manifest& m, std::string_view name) {
  if (m.nodes.empty()) return invalid(name, "no nodes");
  if (!m.texture.empty() && !safe_relative(m.texture))
    return invalid(name, "\"texture\" must be a relative path without '..'");
  const auto count = static_cast<std::int64_t>(m.nodes.size());
  for (std::size_t i = 0; i < m.nodes.size(); ++i) {
    const NodeInfo& n = m.nodes[i];
    const std::string where = "node " + std::to_string(i);
    if (i == 0 ? n.parent != -1 : (n.parent < 0 || n.parent >= static_cast<std::int64_t>(i)))
      return invalid(name, where + ": parent must precede the node (root has none)");
    if (i > 0 && n.depth != m.nodes[static_cast<std::size_t>(n.parent)].depth + 1)
      return invalid(name, where + ": depth is not parent depth + 1");
    if (i == 0 && n.depth != 0) return invalid(name, "root depth must be 0");
    for (std::size_t c = 0; c < 8; ++c) {
      std::int32_t child = n.children[c];
      if (child == -1) continue;
      if (child <= static_cast<std::int64_t>(i) || child >= count)
        return invalid(name, where + ": child index out of range");
      if (m.nodes[static_cast<std::size_t>(child)].parent != static_cast<std::int32_t>(i))
        return invalid(name, where + ": child " + std::to_string(child) + " names another parent");
    }
    if (i > 0) {
      const NodeInfo& parent = m.nodes[static_cast<std::size_t>(n.parent)];
      bool listed = false;
      for (std::int32_t c : parent.children) listed = listed || c == static_cast<std::int32_t>(i);
      if (!listed) return invalid(name, where + ": not listed among its parent's children");
    }
    for (std::size_t l = 0; l < n.lods.size(); ++l) {
      const LodInfo& lod = n.lods[l];
      if (!safe_relative(lod.file))
        return invalid(name, where + " lod " + std::to_string(l) + ": file must be a relative path without '..'");
      if (!(lod.error >= 0.0)) return invalid(name, where + " lod " + std::to_string(l) + ": negative or NaN error");
      if (lod.bytes < kNodeFileHeaderBytes)
        return invalid(name, where + " lod " + std::to_string(l) + ": " + std::to_string(lod.bytes) +
                                 " bytes, less than a node file's header (" + std::to_string(kNodeFileHeaderBytes) + ")");
    }
  }
  return {};
}

namespace {


// `value` as json::dump(1) writes it at nesting `level`: continuation lines get `level` more
// spaces (JSON strings hold no raw newline, so every '\n' is a line break).
void append_nested(std::string& out, const json& value, std::size_t level) {
  const std::string text = value.dump(1);
  for (char c : text) {
    out += c;
    if (c == '\n') out.append(level, ' ');
  }
}

json parameters_to_json(const BakeParameters& p) {
  return {{"input", p.input},
          {"max_tris", p.max_tris},
          {"max_depth", p.max_depth},
          {"memory_budget_bytes", p.memory_budget_bytes},
          {"threads", p.threads},
          {"method", p.method},
          {"lod_ratio", p.lod_ratio}};
}

json node_to_json(const NodeInfo& n) {
  json lods = json::array();
  for (const LodInfo& l : n.lods)
    lods.push_back({{"triangles", l.triangles}, {"vertices", l.vertices}, {"error", l.error},
                    {"bytes", l.bytes}, {"file", l.file}});
  return {{"path", n.path},
          {"depth", n.depth},
          {"parent", n.parent},
          {"children", n.children},
          {"child_mask", n.child_mask()},
          {"cell", bounds_to_json(n.cell)},
          {"bounds", bounds_to_json(n.bounds)},
          {"source_triangles", n.source_triangles},
          {"lods", lods}};
}

// The manifest's text as dump(1) of the whole document would write it (keys sorted, one space
// per level), but for each node, which is one line of its own (dump(), no spaces): with the
// floats' shortest decimals (bounds_to_json), the 10M city's 21,845 nodes take 9.4 MB instead
// of 17.2 MB, and are read 10% faster.
// Handed to `out` piece by piece: the header members, then one node at a time as `node`
// produces it, so the memory is one node's JSON, not the tree's (about 1.5 KB per node as a
// DOM). The first error of `node` or `out` ends it.
Status emit_manifest(const Manifest& m, std::size_t node_count, const ManifestNodeFn& node,
                     const std::function<Status(std::string_view)>& out) {
  json head{{"format", "octolod-manifest"},
                  {"version", m.version},
                  {"layout", layout_to_json(m.layout)},
                  {"origin", m.origin},
                  {"bounds", bounds_to_json(m.bounds)},
                  {"input_vertices", m.input_vertices},
                  {"input_triangles", m.input_triangles},
                  {"parameters", parameters_to_json(m.parameters)},
                  {"stage_seconds", m.stage_seconds},
                  {"stats", m.stats}};
  if (!m.texture.empty()) head["texture"] = m.texture;
  std::string piece = "{\n";
  bool first_member = true;
  const auto start_member = [&](const std::string& key) {
    if (!first_member) piece += ",\n";
    first_member = false;
    piece += ' ';
    piece += json(key).dump();
    piece += ": ";
  };
  const auto emit_nodes = [&]() -> Status {
    start_member("nodes");
    if (node_count == 0) {
      piece += "[]";
      return {};
    }
    piece += "[\n";
    for (std::size_t i = 0; i < node_count; ++i) {
      Result<NodeInfo> n = node(i);
      if (!n.ok()) return n.status();
      piece += "  ";
      piece += node_to_json(n.value()).dump();
      piece += i + 1 < node_count ? ",\n" : "\n ]";
      OCTOLOD_RETURN_IF_ERROR(out(piece));
      piece.clear();
    }
    return {};
  };
  bool nodes_done = false;
  for (const auto& [key, value] : head.items()) {  // sorted by key, as dump() orders them
    if (!nodes_done && key > "nodes") {
      OCTOLOD_RETURN_IF_ERROR(emit_nodes());
      nodes_done = true;
    }
    start_member(key);
    append_nested(piece, value, 1);
  }
  if (!nodes_done) OCTOLOD_RETURN_IF_ERROR(emit_nodes());
  piece += "\n}\n";
  return out(piece);
}

ManifestNodeFn nodes_of(const Manifest& m) {
  return [&m](std::size_t i) -> Result<NodeInfo> { return m.nodes[i]; };
}

}  // namespace

std::string manifest_to_json(const Manifest& m) {
  std::string text;
  const Status done = emit_manifest(m, m.nodes.size(), nodes_of(m), [&](std::string_view piece) {
    text += piece;
    return Status{};
  });
  assert(done.ok());  // neither the nodes nor the string can fail
  (void)done;
  return text;
}

namespace {

// The manifest from `read(sax)` (read_json of a text or a stream into that handler).
template <class Read>
Result<Manifest> manifest_from_reader(const Read& read, std::string_view name) {
  Manifest m;
  ManifestSax sax(m.nodes);
  const JsonReadResult read_result = read(sax);
  if (!read_result.error.empty()) return bad_input_error(std::string(name) + ": not valid JSON: " + read_result.error);
  const json& doc = sax.document();
  try {
    if (doc.at("format").get<std::string>() != "octolod-manifest")
      return invalid(name, "\"format\" is not \"octolod-manifest\"");
    m.version = integer_at<std::uint32_t>(doc, "version");
    if (m.version != kManifestVersion)
      return Status(ErrorCode::unsupported, std::string(name) + ": manifest version " +
                                                std::to_string(m.version) + ", this build reads " +
                                                std::to_string(kManifestVersion));
    if (!sax.node_error().empty()) return invalid(name, sax.node_error());
    const json& layout = doc.at("layout");
    m.layout = VertexLayout{layout.at("normal").get<bool>(), layout.at("color").get<bool>(),
                            layout.at("uv").get<bool>()};
    if (doc.contains("origin")) m.origin = doc.at("origin").get<std::array<double, 3>>();
    for (const double x : m.origin)
      if (!std::isfinite(x)) return invalid(name, "\"origin\" is not finite");
    if (doc.contains("texture")) m.texture = doc.at("texture").get<std::string>();
    m.bounds = bounds_from_json(doc.at("bounds"));
    m.input_vertices = integer_at<std::uint64_t>(doc, "input_vertices");
    m.input_triangles = integer_at<std::uint64_t>(doc, "input_triangles");
    const json& p = doc.at("parameters");
    m.parameters = BakeParameters{p.at("input").get<std::string>(),
                                  integer_at<std::uint32_t>(p, "max_tris"),
                                  integer_at<std::uint32_t>(p, "max_depth"),
                                  integer_at<std::uint64_t>(p, "memory_budget_bytes"),
                                  integer_at<std::uint32_t>(p, "threads"),
                                  p.at("method").get<std::string>()};
    if (p.contains("lod_ratio")) m.parameters.lod_ratio = p.at("lod_ratio").get<double>();
    if (!(m.parameters.lod_ratio > 0.0 && m.parameters.lod_ratio < 1.0))
      return invalid(name, "\"parameters.lod_ratio\" is not in (0, 1)");
    m.stage_seconds = doc.at("stage_seconds").get<std::map<std::string, double>>();
    m.stats = doc.at("stats").get<std::map<std::string, double>>();
    if (!doc.at("nodes").is_array()) return invalid(name, "\"nodes\" is not an array");
  } catch (const json::exception& e) {
    // nlohmann reports missing keys and type mismatches by exception; convert at this boundary
    return invalid(name, (doc.is_object() ? "" : "not a JSON object: ") + without_json_tag(e.what()));
  }
  OCTOLOD_RETURN_IF_ERROR(validate_manifest(m, name));
  return m;
}

}  // namespace

Result<Manifest> manifest_from_json(std::string_view text, std::string_view name) {
  return manifest_from_reader([&](ManifestSax& sax) { return read_json(text, sax); }, name);
}

Status write_manifest(const std::filesystem::path& path, const Manifest& manifest) {
  return write_manifest(path, manifest, manifest.nodes.size(), nodes_of(manifest));
}

Status write_manifest(const std::filesystem::path& path, const Manifest& header,
                      std::size_t node_count, const ManifestNodeFn& node) {
  std::filesystem::path tmp = path;
  tmp += ".tmp-" + std::to_string(::getpid());
  std::FILE* f = std::fopen(tmp.c_str(), "wb");
  if (!f) return io_error(tmp.string() + ": cannot create: " + std::strerror(errno));
  const auto write_failed = [&] { return io_error(path.string() + ": write failed: " + std::strerror(errno)); };
  Status status = emit_manifest(header, node_count, node, [&](std::string_view piece) -> Status {
    if (std::fwrite(piece.data(), 1, piece.size(), f) == piece.size()) return {};
    return write_failed();
  });
  if (status.ok() && std::fflush(f) != 0) status = write_failed();
  if (std::fclose(f) != 0 && status.ok()) status = write_failed();
  std::error_code ec;
  if (!status.ok()) {
    std::filesystem::remove(tmp, ec);
    return status;
  }
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::filesystem::remove(tmp, ec);
    return io_error(path.string() + ": rename failed: " + ec.message());
  }
  return {};
}

std::string bake_parameters_to_json(const BakeParameters& parameters) {
  return parameters_to_json(parameters).dump();
}

Result<Manifest> read_tree_manifest(const std::filesystem::path& tree_root) {
  return read_manifest(tree_root / kManifestFileName);
}

Result<Manifest> read_manifest(const std::filesystem::path& path) {
  OCTOLOD_RETURN_IF_ERROR(check_input_file(path, "the manifest"));
  std::ifstream in(path, std::ios::binary);
  if (!in) return io_error(path.string() + ": cannot open: " + std::strerror(errno));
  // parsed from the stream: a large tree's text is never held whole (180 MB for 100M triangles)
  Result<Manifest> manifest =
      manifest_from_reader([&](ManifestSax& sax) { return read_json(in, sax); }, path.string());
  if (in.bad()) return io_error(path.string() + ": read failed");
  return manifest;
}

Status check_node_lod(const NodeMesh& mesh, const LodInfo& lod, const VertexLayout& layout, std::string_view name) {
  if (mesh.layout != layout)
    return bad_input_error(std::string(name) + ": vertex layout " + mesh.layout.describe() + " differs from the manifest's " +
                           layout.describe());
  if (mesh.triangle_count() != lod.triangles || mesh.vertex_count() != lod.vertices)
    return bad_input_error(std::string(name) + ": holds " + std::to_string(mesh.triangle_count()) + " triangles and " +
                           std::to_string(mesh.vertex_count()) + " vertices, the manifest says " +
                           std::to_string(lod.triangles) + " and " + std::to_string(lod.vertices) +
                           " (a node file from elsewhere, or an edited manifest)");
  return {};
}

}  // namespace octolod
