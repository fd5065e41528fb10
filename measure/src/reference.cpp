// QSlim-style reference simplification (Garland & Heckbert 1997) with OpenMesh's Decimater:
// weld by position, greedy quadric-ordered half-edge collapses with a normal-flip veto, then
// attributes re-sampled from the input at each output vertex's closest point.
#include "octolod/measure/reference.h"

#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>
#include <optional>
#include <unordered_map>
#include <vector>

#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Core/System/omstream.hh>
#include <OpenMesh/Tools/Decimater/DecimaterT.hh>
#include <OpenMesh/Tools/Decimater/ModNormalFlippingT.hh>
#include <OpenMesh/Tools/Decimater/ModQuadricT.hh>
#include <glm/geometric.hpp>

#include "mesh_check.h"
#include "octolod/measure/triangle_bvh.h"
#include "valence_limit.h"

namespace octolod::measure {
namespace {

using OmMesh = OpenMesh::TriMesh_ArrayKernelT<>;

struct PositionKey {
  std::uint32_t x, y, z;
  friend bool operator==(const PositionKey&, const PositionKey&) = default;
};
struct PositionKeyHash {
  std::size_t operator()(const PositionKey& k) const {
    std::uint64_t h = k.x * 0x9E3779B97F4A7C15ull;
    h ^= (h >> 29) + k.y * 0xBF58476D1CE4E5B9ull;
    h ^= (h >> 31) + k.z * 0x94D049BB133111EBull;
    return static_cast<std::size_t>(h ^ (h >> 32));
  }
};

// -0.0 and +0.0 are the same position.
std::uint32_t position_bits(float f) { return std::bit_cast<std::uint32_t>(f + 0.0f); }

// Welds `input`'s vertices by exact position into `mesh`; returns the OpenMesh vertex of every
// input vertex.
std::vector<OmMesh::VertexHandle> weld_vertices(const NodeMesh& input, OmMesh& mesh) {
  const std::uint32_t stride = input.layout.floats();
  std::unordered_map<PositionKey, OmMesh::VertexHandle, PositionKeyHash> first_at;
  first_at.reserve(input.vertex_count());
  std::vector<OmMesh::VertexHandle> handle(input.vertex_count());
  for (std::size_t v = 0; v < input.vertex_count(); ++v) {
    const float* p = input.vertices.data() + v * stride;
    PositionKey key{position_bits(p[0]), position_bits(p[1]), position_bits(p[2])};
    auto [it, inserted] = first_at.try_emplace(key);
    if (inserted) it->second = mesh.add_vertex(OmMesh::Point(p[0], p[1], p[2]));
    handle[v] = it->second;
  }
  return handle;
}

// Adds the triangles; those the half-edge structure rejects (non-manifold) are added as detached
// copies with vertices of their own. Returns how many were detached.
std::uint64_t add_triangles(const NodeMesh& input, const std::vector<OmMesh::VertexHandle>& handle,
                            OmMesh& mesh) {
  std::uint64_t detached = 0;
  for (std::size_t t = 0; t < input.triangle_count(); ++t) {
    OmMesh::VertexHandle a = handle[input.indices[3 * t]], b = handle[input.indices[3 * t + 1]],
                         c = handle[input.indices[3 * t + 2]];
    if (a == b || b == c || c == a) continue;  // degenerate after welding
    if (mesh.add_face(a, b, c).is_valid()) continue;
    // copies: point() refers into the vertex array, which add_vertex may reallocate
    const OmMesh::Point pa = mesh.point(a), pb = mesh.point(b), pc = mesh.point(c);
    OmMesh::VertexHandle a2 = mesh.add_vertex(pa), b2 = mesh.add_vertex(pb), c2 = mesh.add_vertex(pc);
    mesh.add_face(a2, b2, c2);
    ++detached;
  }
  return detached;
}

using Decimater = OpenMesh::Decimater::DecimaterT<OmMesh>;

std::size_t count_live_faces(const OmMesh& mesh) {
  std::size_t live = 0;
  for ([[maybe_unused]] OmMesh::FaceHandle fh : mesh.faces()) ++live;
  return live;
}

// The valence no collapse may raise a vertex above (ModValenceLimitT). On the 200K rock, city
// and terrain it never binds (their references at 1% and 3% are byte-identical without it; the
// largest valence in them is 12); on a 32-sided open tube of 32,000 triangles it takes the
// decimation to 1% from 104 s to 0.5 s, with a two-sided RMS of 0.012 instead of 0.021 (a limit
// of 32: 0.9 s, RMS 0.075).
constexpr unsigned kMaxValence = 16;

// Greedy quadric-ordered half-edge collapses; lives as long as the snapshots are taken, so the
// vertex quadrics accumulate across targets.
class QuadricDecimation {
 public:
  explicit QuadricDecimation(OmMesh& mesh) : mesh_(mesh), decimater_(mesh) {
    decimater_.add(quadric_);
    decimater_.add(normal_flipping_);
    decimater_.add(valence_limit_);
    decimater_.module(valence_limit_).set_max_valence(kMaxValence);
    decimater_.module(quadric_).unset_max_err();  // priority only: stop at the count, not an error
    decimater_.initialize();
  }
  // Collapses until at most `target_triangles` faces are live; returns the live face count.
  // decimate_to_faces counts faces with mesh.n_faces(), which includes the faces deleted by
  // earlier calls (they stay until garbage collection), so the target is offset by those.
  std::size_t run_to(std::size_t live_faces, std::uint32_t target_triangles) {
    const std::size_t deleted = mesh_.n_faces() - live_faces;
    decimater_.decimate_to_faces(0, deleted + target_triangles);
    return count_live_faces(mesh_);
  }

 private:
  OmMesh& mesh_;
  Decimater decimater_;
  OpenMesh::Decimater::ModQuadricT<OmMesh>::Handle quadric_;
  OpenMesh::Decimater::ModNormalFlippingT<OmMesh>::Handle normal_flipping_;
  ModValenceLimitT<OmMesh>::Handle valence_limit_;
};

// Attributes of the input at its point closest to a position: what an output vertex carries.
class AttributeSampler {
 public:
  explicit AttributeSampler(const NodeMesh& input) : input_(input), stride_(input.layout.floats()) {
    if (stride_ > 3) bvh_ = TriangleBvh(input.vertices, stride_, input.indices);
  }

  // Writes position `p` and its attributes (renormalized normal, clamped colour) to dst[0..stride).
  void sample(const OmMesh::Point& p, float* dst) const {
    dst[0] = p[0];
    dst[1] = p[1];
    dst[2] = p[2];
    if (stride_ == 3) return;
    const TriangleBvh::Hit hit = bvh_.closest({p[0], p[1], p[2]});
    const std::size_t first = 3 * std::size_t{hit.triangle};
    for (std::uint32_t k = 3; k < stride_; ++k) {
      float value = 0.0f;
      for (std::size_t c = 0; c < 3; ++c)
        value += hit.barycentric[static_cast<glm::length_t>(c)] *
                 input_.vertices[std::size_t{input_.indices[first + c]} * stride_ + k];
      dst[k] = value;
    }
    if (input_.layout.normal) {
      glm::vec3 n(dst[3], dst[4], dst[5]);
      const float length = glm::length(n);
      if (length > 0.0f) n /= length;
      dst[3] = n.x;
      dst[4] = n.y;
      dst[5] = n.z;
    }
    if (input_.layout.color)
      for (std::uint32_t k = 0; k < 3; ++k) {
        float& c = dst[input_.layout.color_offset() + k];
        c = std::clamp(c, 0.0f, 1.0f);
      }
  }

 private:
  const NodeMesh& input_;
  std::uint32_t stride_;
  TriangleBvh bvh_;
};

// The current state of `mesh` as a NodeMesh: its live faces and the vertices they use (vertices
// left isolated by welding or by the decimater are dropped), attributes from the input.
NodeMesh snapshot(const OmMesh& mesh, const AttributeSampler& sampler, VertexLayout layout) {
  constexpr std::uint32_t kUnused = ~0u;
  std::vector<std::uint32_t> index(mesh.n_vertices(), kUnused);
  for (OmMesh::FaceHandle fh : mesh.faces())
    for (OmMesh::VertexHandle vh : mesh.fv_range(fh)) index[static_cast<std::size_t>(vh.idx())] = 0;
  std::uint32_t used = 0;
  for (std::uint32_t& i : index)
    if (i != kUnused) i = used++;

  NodeMesh out;
  out.layout = layout;
  const std::uint32_t stride = layout.floats();
  out.vertices.resize(std::size_t{used} * stride);
  for (std::size_t v = 0; v < index.size(); ++v)
    if (index[v] != kUnused)
      sampler.sample(mesh.point(OmMesh::VertexHandle(static_cast<int>(v))),
                     out.vertices.data() + std::size_t{index[v]} * stride);
  out.indices.reserve(mesh.n_faces() * 3);
  for (OmMesh::FaceHandle fh : mesh.faces())
    for (OmMesh::VertexHandle vh : mesh.fv_range(fh))
      out.indices.push_back(index[static_cast<std::size_t>(vh.idx())]);
  return out;
}

}  // namespace

Result<std::vector<NodeMesh>> reference_simplify_ladder(const NodeMesh& input,
                                                        std::span<const std::uint32_t> targets,
                                                        ReferenceStats* stats) {
  const auto start = std::chrono::steady_clock::now();
  if (targets.empty()) return usage_error("reference: no target triangle count given");
  if (std::find(targets.begin(), targets.end(), 0u) != targets.end())
    return usage_error("reference: the target triangle count must be > 0");
  OCTOLOD_RETURN_IF_ERROR(check_mesh(input, "reference input"));

  OmMesh mesh;
  // Held for the whole function: the decimater needs the status flags, and the snapshots skip
  // the elements it deleted.
  mesh.request_vertex_status();
  mesh.request_edge_status();
  mesh.request_face_status();
  // the normal-flip module compares face normals before and after a collapse
  mesh.request_face_normals();
  mesh.reserve(input.vertex_count(), input.triangle_count() * 3 / 2, input.triangle_count());
  std::vector<OmMesh::VertexHandle> handle = weld_vertices(input, mesh);
  const std::uint64_t welded_vertices = mesh.n_vertices();
  // OpenMesh reports rejected (non-manifold) faces on its error stream; they are counted instead
  ::omerr().disable();
  const std::uint64_t detached = add_triangles(input, handle, mesh);
  ::omerr().enable();
  handle = {};
  mesh.update_face_normals();

  // largest target first; each snapshot is taken once the live face count is at its target
  std::vector<std::size_t> order(targets.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return targets[a] > targets[b]; });
  const AttributeSampler sampler(input);
  std::vector<NodeMesh> results(targets.size());
  std::optional<QuadricDecimation> decimation;
  std::size_t live_faces = mesh.n_faces();
  for (std::size_t i : order) {
    if (live_faces > targets[i]) {
      if (!decimation) decimation.emplace(mesh);
      live_faces = decimation->run_to(live_faces, targets[i]);
    }
    results[i] = snapshot(mesh, sampler, input.layout);
  }

  if (stats) {
    stats->input_triangles = input.triangle_count();
    stats->welded_vertices = welded_vertices;
    stats->detached_triangles = detached;
    stats->output_triangles = results[order.back()].triangle_count();
    stats->seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  return results;
}

Result<NodeMesh> reference_simplify(const NodeMesh& input, std::uint32_t target_triangles,
                                    ReferenceStats* stats) {
  const std::uint32_t targets[] = {target_triangles};
  Result<std::vector<NodeMesh>> results = reference_simplify_ladder(input, targets, stats);
  if (!results.ok()) return results.status();
  return std::move(results.value().front());
}

}  // namespace octolod::measure
