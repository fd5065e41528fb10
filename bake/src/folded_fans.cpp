// folded_fans.h: one pass over the wedges with three triangles (the output's corners per wedge
// in a CSR), with a table of the output's cluster triples once a folded fan needs it.
#include "folded_fans.h"

#include <algorithm>
#include <array>
#include <optional>

#include "flat_hash.h"
#include "wedges.h"

namespace octolod::bake {
namespace {

// The replacement must lower the farthest squared distance by this share.
constexpr double kMinGain = 0.05;
constexpr std::uint32_t kNotReplaced = 0xFFFFFFFFu;

// The input vertices of every wedge: `vertex` in CSR order, the offsets returned.
std::vector<std::uint32_t> wedge_vertices(const ClusteredOutput& out, std::vector<std::uint32_t>& vertex) {
  std::vector<std::uint32_t> offset(out.wedge_cluster.size() + 1, 0);
  for (std::uint32_t w : out.vertex_wedge) ++offset[w + 1];
  for (std::size_t w = 0; w + 1 < offset.size(); ++w) offset[w + 1] += offset[w];
  vertex.resize(out.vertex_wedge.size());
  std::vector<std::uint32_t> fill(offset.begin(), offset.end() - 1);
  for (std::uint32_t u = 0; u < out.vertex_wedge.size(); ++u) vertex[fill[out.vertex_wedge[u]]++] = u;
  return offset;
}

}  // namespace

FoldRepair remove_folded_fans(InputDistances& input, std::vector<std::uint32_t>& corners) {
  const ClusteredOutput& out = input.output();
  const std::size_t triangle_count = corners.size() / 3;
  const std::size_t wedge_count = out.wedge_cluster.size();
  auto cluster_of = [&](std::size_t corner) { return out.wedge_cluster[corners[corner]]; };

  // the corners at every wedge (CSR), and every triangle's cluster triple
  std::vector<std::uint32_t> offset(wedge_count + 1, 0);
  for (std::uint32_t w : corners) ++offset[w + 1];
  for (std::size_t w = 0; w < wedge_count; ++w) offset[w + 1] += offset[w];
  std::vector<std::uint32_t> corner_at(corners.size());
  {
    std::vector<std::uint32_t> fill(offset.begin(), offset.end() - 1);
    for (std::size_t corner = 0; corner < corners.size(); ++corner)
      corner_at[fill[corners[corner]]++] = static_cast<std::uint32_t>(corner);
  }
  // every triangle's cluster triple, tabled at the first folded fan (most nodes have none)
  std::optional<FlatHashMap<3>> triples;
  auto table_triples = [&] {
    triples.emplace(triangle_count + triangle_count / 3 + 1);
    for (std::size_t t = 0; t < triangle_count; ++t) {
      bool inserted = false;
      triples->find_or_insert(sorted_triple(cluster_of(3 * t), cluster_of(3 * t + 1), cluster_of(3 * t + 2)), 0,
                              inserted);
    }
  };

  // triangles removed or rewritten: a fan with one of them waits for another bake
  std::vector<std::uint8_t> changed(triangle_count, 0);
  std::vector<std::uint32_t> replaced_by(triangle_count, kNotReplaced);  // a removed one's replacement
  std::vector<std::array<std::uint32_t, 2>> replaced;  // (v's cluster, replacement) per fan
  std::optional<std::vector<std::uint32_t>> wedge_offset;  // the input vertices of every wedge
  std::vector<std::uint32_t> wedge_vertex;
  for (std::uint32_t v = 0; v < wedge_count; ++v) {
    if (offset[v + 1] - offset[v] != 3) continue;
    // per triangle of the fan: the wedges after v in its winding, (next, previous)
    std::array<std::size_t, 3> triangle;
    std::array<std::uint32_t, 3> next, previous;
    bool usable = true;
    for (std::size_t i = 0; i < 3; ++i) {
      const std::uint32_t corner = corner_at[offset[v] + i];
      triangle[i] = corner / 3;
      usable = usable && !changed[triangle[i]];
      const std::size_t base = corner - corner % 3;
      next[i] = corners[base + (corner % 3 + 1) % 3];
      previous[i] = corners[base + (corner % 3 + 2) % 3];
    }
    if (!usable) continue;
    // three neighbour clusters, each in two of the triangles (a closed fan); folded when some
    // spoke runs the same way in both of its triangles (a neighbour twice among `next` or among
    // `previous`)
    std::array<std::uint32_t, 3> neighbour{};  // a wedge of each, the first met
    std::array<int, 3> uses{};
    std::size_t neighbours = 0;
    auto count = [&](std::uint32_t wedge) {
      for (std::size_t k = 0; k < std::min<std::size_t>(neighbours, 3); ++k)
        if (out.wedge_cluster[neighbour[k]] == out.wedge_cluster[wedge]) {
          ++uses[k];
          return;
        }
      if (neighbours < 3) neighbour[neighbours] = wedge, uses[neighbours] = 1;
      ++neighbours;
    };
    for (std::size_t i = 0; i < 3; ++i) count(next[i]), count(previous[i]);
    if (neighbours != 3 || uses != std::array<int, 3>{2, 2, 2}) continue;
    auto same = [&](std::uint32_t x, std::uint32_t y) { return out.wedge_cluster[x] == out.wedge_cluster[y]; };
    const bool folded = same(next[0], next[1]) || same(next[1], next[2]) || same(next[0], next[2]) ||
                        same(previous[0], previous[1]) || same(previous[1], previous[2]) ||
                        same(previous[0], previous[2]);
    if (!folded) continue;

    // the replacement, of the neighbours' first wedges, wound like most of the fan's outer edges
    // (next -> previous); no triangle may join the three clusters yet (it would be used twice)
    auto first_wedge = [&](std::uint32_t wedge) {
      for (std::uint32_t w : neighbour)
        if (same(w, wedge)) return w;
      return wedge;
    };
    const std::uint32_t a = first_wedge(next[0]), b = first_wedge(previous[0]);
    std::uint32_t c = neighbour[0];
    for (std::uint32_t w : neighbour)
      if (!same(w, a) && !same(w, b)) c = w;
    int agree = 0;
    for (std::size_t i = 0; i < 3; ++i) {
      const std::uint32_t n = first_wedge(next[i]), p = first_wedge(previous[i]);
      agree += (n == a && p == b) || (n == b && p == c) || (n == c && p == a);
    }
    const std::array<std::uint32_t, 3> replacement = agree >= 2 ? std::array{a, b, c} : std::array{b, a, c};
    const auto triple = sorted_triple(out.wedge_cluster[a], out.wedge_cluster[b], out.wedge_cluster[c]);
    if (!triples) table_triples();
    if (triples->find(triple) != FlatHashMap<3>::kMissing) continue;

    // judged like a flip: the spokes' middles against the replacement's centroid, and the input
    // vertices of v's wedge against the replacement (what it leaves them)
    const Vec3d pv = out.wedge_position(v), pa = out.wedge_position(a), pb = out.wedge_position(b),
                pc = out.wedge_position(c);
    const std::array<std::uint32_t, 4> clusters{out.wedge_cluster[v], triple[0], triple[1], triple[2]};
    const std::array<Vec3d, 4> points{midpoint(pv, pa), midpoint(pv, pb), midpoint(pv, pc), centroid(pa, pb, pc)};
    std::array<double, 4> distance2;
    input.nearest2(clusters, points, distance2);
    const double before = std::max({distance2[0], distance2[1], distance2[2]});
    double after = distance2[3];
    if (!wedge_offset) wedge_offset = wedge_vertices(out, wedge_vertex);
    const std::size_t stride = out.input.layout.floats();
    for (std::uint32_t i = (*wedge_offset)[v]; i < (*wedge_offset)[v + 1]; ++i) {
      const float* f = &out.input.vertices[wedge_vertex[i] * stride];
      after = std::max(after, point_triangle_distance2({f[0], f[1], f[2]}, pa, pb, pc));
    }
    if (!(after < (1.0 - kMinGain) * before)) continue;

    bool inserted = false;
    triples->find_or_insert(triple, 0, inserted);
    std::copy(replacement.begin(), replacement.end(), corners.begin() + static_cast<std::ptrdiff_t>(3 * triangle[0]));
    for (std::size_t t : triangle) changed[t] = 1;
    replaced_by[triangle[1]] = replaced_by[triangle[2]] = static_cast<std::uint32_t>(triangle[0]);
    replaced.push_back({out.wedge_cluster[v], static_cast<std::uint32_t>(triangle[0])});
  }

  FoldRepair repair;
  std::vector<std::uint32_t>& index = repair.index;
  index.resize(triangle_count);
  std::size_t kept = 0;
  for (std::size_t t = 0; t < triangle_count; ++t) {
    if (replaced_by[t] != kNotReplaced) continue;
    index[t] = static_cast<std::uint32_t>(kept);
    std::copy_n(corners.begin() + static_cast<std::ptrdiff_t>(3 * t), 3, corners.begin() + static_cast<std::ptrdiff_t>(3 * kept));
    ++kept;
  }
  for (std::size_t t = 0; t < triangle_count; ++t)
    if (replaced_by[t] != kNotReplaced) index[t] = index[replaced_by[t]];
  corners.resize(3 * kept);
  for (auto [cluster, triangle] : replaced) repair.fan_extra.push_back({cluster, index[triangle]});
  return repair;
}

}  // namespace octolod::bake
