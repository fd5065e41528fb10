// inside_out.h: with normals, one pass over the triangles finds the few that face against their
// corners' normals; then the directed edges (position ids) go into buckets by their first end
// (a counting sort), so that the triangles at an edge are found among the few edges leaving one
// position. The decisions read only the mesh as it was, so they do not depend on the order of
// the re-windings.
#include "inside_out.h"

#include <array>
#include <cstdint>
#include <utility>
#include <vector>

#include "boundary_edges.h"
#include "point_triangle.h"
#include "wedges.h"

namespace octolod::bake {
namespace {

struct OutEdge {
  std::uint32_t to;        // position id of its second end
  std::uint32_t triangle;  // the triangle that runs it
};

}  // namespace

std::size_t rewind_inside_out(NodeMesh& mesh) {
  const std::size_t triangle_count = mesh.triangle_count();
  if (triangle_count < 2) return 0;
  const std::size_t stride = mesh.layout.floats();
  auto record_of = [&](std::size_t corner) { return &mesh.vertices[mesh.indices[corner] * stride]; };
  auto normal_of = [&](std::size_t t) { return triangle_normal(record_of(3 * t), record_of(3 * t + 1), record_of(3 * t + 2)); };
  // With normals, the suspects are the triangles that face against the mean of their corners'
  // (about 1 in 1,000 of a rock's): most steps have none and build nothing below.
  std::vector<std::uint32_t> suspects;
  for (std::size_t t = 0; t < triangle_count; ++t) {
    if (mesh.layout.normal) {
      std::array<double, 3> corners{0.0, 0.0, 0.0};
      for (std::size_t k = 0; k < 3; ++k)
        for (std::size_t i = 0; i < 3; ++i) corners[i] += record_of(3 * t + k)[VertexLayout::normal_offset() + i];
      if (dot(normal_of(t), corners) >= 0.0) continue;
    }
    suspects.push_back(static_cast<std::uint32_t>(t));
  }
  if (suspects.empty()) return 0;

  // every triangle's normal, and its directed edges (corner k to k + 1) by their first end (CSR)
  const PositionIds positions = make_position_ids(mesh);
  auto position_of = [&](std::size_t corner) { return positions.of_vertex[mesh.indices[corner]]; };
  std::vector<std::array<double, 3>> normal(triangle_count);
  std::vector<std::uint32_t> offset(std::size_t{positions.count} + 1, 0);
  for (std::size_t corner = 0; corner < 3 * triangle_count; ++corner) ++offset[position_of(corner) + 1];
  for (std::size_t p = 0; p < positions.count; ++p) offset[p + 1] += offset[p];
  std::vector<OutEdge> out(3 * triangle_count);
  {
    std::vector<std::uint32_t> fill(offset.begin(), offset.end() - 1);
    for (std::size_t t = 0; t < triangle_count; ++t) {
      normal[t] = normal_of(t);
      for (std::size_t k = 0; k < 3; ++k)
        out[fill[position_of(3 * t + k)]++] = {position_of(3 * t + (k + 1) % 3), static_cast<std::uint32_t>(t)};
    }
  }
  // the other triangles that run a -> b: how many, and their normals added to `sum`
  auto runs = [&](std::uint32_t a, std::uint32_t b, std::size_t except, std::array<double, 3>& sum) {
    std::size_t count = 0;
    for (std::uint32_t i = offset[a]; i < offset[a + 1]; ++i) {
      if (out[i].to != b || out[i].triangle == except) continue;
      ++count;
      for (std::size_t j = 0; j < 3; ++j) sum[j] += normal[out[i].triangle][j];
    }
    return count;
  };

  std::vector<std::uint32_t> inside_out;
  for (const std::uint32_t t : suspects) {
    const std::array<std::uint32_t, 3> p{position_of(3 * t), position_of(3 * t + 1), position_of(3 * t + 2)};
    if (p[0] == p[1] || p[1] == p[2] || p[0] == p[2]) continue;
    std::size_t shared = 0;  // edges with neighbours
    bool alike_only = true;  // every neighbour runs its edge as this triangle does
    std::array<double, 3> neighbours{0.0, 0.0, 0.0};
    for (std::size_t k = 0; k < 3; ++k) {
      const std::uint32_t a = p[k], b = p[(k + 1) % 3];
      const std::size_t alike = runs(a, b, t, neighbours), opposite = runs(b, a, t, neighbours);
      shared += alike + opposite > 0;
      alike_only = alike_only && opposite == 0;
    }
    if (shared < 2 || dot(normal[t], neighbours) >= 0.0 || !(mesh.layout.normal || alike_only)) continue;
    // A two-sided sheet's twin (the same corners wound the other way) is left as it is: re-wound,
    // it would repeat the other copy, which the next step drops (a repeated face), and the
    // boundary mod 2 would change.
    bool twin = false;
    for (std::uint32_t i = offset[p[1]]; i < offset[p[1] + 1] && !twin; ++i) {
      const std::uint32_t u = out[i].triangle;
      if (out[i].to != p[0] || u == t) continue;
      for (std::size_t k = 0; k < 3; ++k) twin = twin || position_of(3 * std::size_t{u} + k) == p[2];
    }
    if (!twin) inside_out.push_back(t);
  }
  for (const std::uint32_t t : inside_out) std::swap(mesh.indices[3 * std::size_t{t} + 1], mesh.indices[3 * std::size_t{t} + 2]);
  return inside_out.size();
}

}  // namespace octolod::bake
