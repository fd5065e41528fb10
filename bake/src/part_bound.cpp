// part_bound.h: the single candidate, the prism pieces, the split refinement.
#include "part_bound.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>

namespace octolod::bake {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();
// A split part is not split further when its bound is within 5% of its corners' distances
// (squared here): no split goes below those.
constexpr double kCloseEnough2 = 1.05 * 1.05;
// The prism pieces' areas add up to their part's when they do within this share (with the
// closure test of prism_bound2, that they cover it).
constexpr double kCoverTolerance = 1e-9;

// |x - corner| bounds dist(x, T) from above: a corner of T within sqrt(limit2) of x settles x.
// All three are measured: which one settles x is a coin toss, and a test of each in turn was a
// mispredicted branch.
bool near_corner(const Vec3d& x, const Triangle3d& tri, double limit2) {
  bool near = false;
  for (const Vec3d& corner : tri) {
    const Vec3d d = sub(x, corner);
    near |= dot(d, d) <= limit2;
  }
  return near;
}

// Whether list[0, count) holds `value`, every entry compared: the lists are a prism's few pieces,
// and a search that stopped at the match mispredicted where it stopped.
bool holds(const std::uint32_t* list, std::size_t count, std::uint32_t value) {
  bool found = false;
  for (std::size_t i = 0; i < count; ++i) found |= list[i] == value;
  return found;
}

// Points and convex polygons in a plane's coordinates (a part clipped by a prism's sides). Each
// corner knows the lines it lies on (bits 0-2: the prism's sides, 3-5: the part's own sides), so
// that a piece's sides along a prism side are known without comparing coordinates.
using Point2 = std::array<double, 2>;
struct Polygon {
  std::array<Point2, 9> corner;
  std::array<std::uint8_t, 9> on{};
  std::size_t size = 0;
};
constexpr std::uint8_t kPartSide0 = 1u << 3, kPartSide1 = 1u << 4, kPartSide2 = 1u << 5;
constexpr unsigned kPartSides = kPartSide0 | kPartSide1 | kPartSide2;

// A hash of a position: equal positions (+0 and -0 alike) have equal keys.
std::uint64_t position_key(const Vec3d& p) {
  std::uint64_t key = 0;
  for (const double x : p)
    key = (key ^ std::bit_cast<std::uint64_t>(x == 0.0 ? 0.0 : x)) * 0x9E3779B97F4A7C15ull + (key >> 29);
  return key;
}

// A signature of the directed edge from a position to another, from their keys.
std::uint32_t edge_signature(std::uint64_t from, std::uint64_t to) {
  const std::uint64_t h = (from * 0xC2B2AE3D27D4EB4Full) ^ (to + (to >> 31));
  return static_cast<std::uint32_t>(h ^ (h >> 32));
}

// Twice the signed area of (a, b, p): positive when p is left of a -> b.
double left_of(const Point2& a, const Point2& b, const Point2& p) {
  return (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0]);
}

// left_of(a, b, p), 0 within `on_line` of the line: rounding puts a corner the part shares with
// an output triangle on either side of that triangle's sides.
double side_of(const Point2& a, const Point2& b, const Point2& p, double on_line) {
  const double h = left_of(a, b, p);
  return std::abs(h) <= on_line ? 0.0 : h;
}

// `kept` = the part of `polygon` left of the prism's side `line`, given side_of that line for
// each of its corners in `h`. (Into the caller's polygon: returned, it was copied back whole.)
void clip(const Polygon& polygon, const std::array<double, 9>& h, std::size_t line, Polygon& kept) {
  const auto bit = static_cast<std::uint8_t>(1u << line);
  std::size_t size = 0;
  for (std::size_t k = 0; k < polygon.size; ++k) {
    const std::size_t next = k + 1 == polygon.size ? 0 : k + 1;
    const Point2& p0 = polygon.corner[k];
    const Point2& p1 = polygon.corner[next];
    const double h0 = h[k], h1 = h[next];
    if (h0 >= 0.0) {
      kept.on[size] = static_cast<std::uint8_t>(polygon.on[k] | (h0 == 0.0 ? bit : 0u));
      kept.corner[size++] = p0;
    }
    if (((h0 > 0.0) & (h1 < 0.0)) | ((h0 < 0.0) & (h1 > 0.0))) {  // one branch, not four
      const double t = h0 / (h0 - h1);
      kept.on[size] = static_cast<std::uint8_t>((polygon.on[k] & polygon.on[next]) | bit);
      kept.corner[size++] = {p0[0] + t * (p1[0] - p0[0]), p0[1] + t * (p1[1] - p0[1])};
    }
  }
  kept.size = size;
}

// `candidates` with the triangles of `queries` nearest to `points` joined (sorted, distinct; held
// in `storage`), or `candidates` as they are without queries.
std::span<const std::uint32_t> with_nearest(std::span<const std::uint32_t> candidates, std::span<const Vec3d> points,
                                            const measure::TriangleBvh* queries, std::vector<std::uint32_t>& storage) {
  if (queries == nullptr) return candidates;
  storage.assign(candidates.begin(), candidates.end());
  for (const Vec3d& p : points) storage.push_back(closest_triangle(*queries, p));
  std::sort(storage.begin(), storage.end());
  storage.erase(std::unique(storage.begin(), storage.end()), storage.end());
  return storage;
}

// The directed edges 3 t + k of a triangle list (corner k to k + 1), found by the positions of
// their ends: chained by the signatures of those positions as they run.
class DirectedEdges {
 public:
  explicit DirectedEdges(std::span<const Triangle3d> triangles)
      : triangles_(triangles), signature_(3 * triangles.size()), back_(3 * triangles.size()),
        next_(3 * triangles.size()), head_(std::bit_ceil(std::max<std::size_t>(16, 6 * triangles.size())), kNoEdge),
        mask_(head_.size() - 1) {
    for (std::size_t t = 0; t < triangles.size(); ++t) {
      const Triangle3d& tri = triangles[t];
      const std::array<std::uint64_t, 3> key{position_key(tri[0]), position_key(tri[1]), position_key(tri[2])};
      for (std::size_t k = 0; k < 3; ++k) {
        const std::size_t edge = 3 * t + k;
        signature_[edge] = edge_signature(key[k], key[k + 1 == 3 ? 0 : k + 1]);
        back_[edge] = edge_signature(key[k + 1 == 3 ? 0 : k + 1], key[k]);
        next_[edge] = head_[signature_[edge] & mask_];
        head_[signature_[edge] & mask_] = static_cast<std::uint32_t>(edge);
      }
    }
  }
  // Calls visit(m) for each edge m of another triangle that runs the positions of `edge` the
  // same way (backwards false) or backwards, until it returns true.
  template <class Visit>
  void others(std::size_t edge, bool backwards, Visit&& visit) const {
    const std::size_t t = edge / 3, k = edge % 3;
    const Vec3d& a = triangles_[t][k];
    const Vec3d& b = triangles_[t][k + 1 == 3 ? 0 : k + 1];
    const Vec3d &from = backwards ? b : a, &to = backwards ? a : b;
    const std::uint32_t wanted = backwards ? back_[edge] : signature_[edge];
    for (std::uint32_t m = head_[wanted & mask_]; m != kNoEdge; m = next_[m]) {
      const Triangle3d& other = triangles_[m / 3];
      const std::size_t j = m % 3;
      if (m / 3 != t && signature_[m] == wanted && other[j] == from && other[j + 1 == 3 ? 0 : j + 1] == to && visit(m))
        return;
    }
  }

 private:
  static constexpr std::uint32_t kNoEdge = 0xFFFFFFFFu;
  std::span<const Triangle3d> triangles_;
  std::vector<std::uint32_t> signature_, back_, next_, head_;
  std::size_t mask_;
};

using Across = std::array<std::uint32_t, 3>;

// Per triangle and edge k (corner k to k + 1): the first other triangle that runs it backwards.
std::vector<Across> triangles_across(std::size_t triangle_count, const DirectedEdges& edges) {
  std::vector<Across> across(triangle_count, {kNoTriangle, kNoTriangle, kNoTriangle});
  for (std::size_t t = 0; t < triangle_count; ++t)
    for (std::size_t k = 0; k < 3; ++k)
      edges.others(3 * t + k, true, [&](std::uint32_t m) {
        across[t][k] = m / 3;
        return true;
      });
  return across;
}

// Which triangles to re-wind so that across every shared edge the two triangles run it
// opposite ways, where they can: in each connected piece whose winding is inconsistent, the
// part of the smaller area. Empty when none needs it. An inconsistently wound output keeps the
// prism pieces from tiling a part's shadow (they take the candidates facing like the part).
// Inconsistent means at least a quarter of the piece's shared edges have only triangles that run
// them alike (just one) on the other side (on 1M rocks at most 7%: the clustering's folds,
// triangles re-wound to face like their sources, which the prism needs as they are; a mesh
// wound at random: 45-55%). `across` is triangles_across; `normal`, per triangle, twice its area
// times its unit normal.
std::vector<std::uint8_t> rewinding(std::span<const Vec3d> normal, const DirectedEdges& edges,
                                    const std::vector<Across>& across) {
  const std::size_t triangle_count = normal.size();
  const std::size_t edge_count = 3 * triangle_count;
  std::vector<std::uint32_t> neighbour(edge_count, kNoTriangle);
  std::vector<std::uint8_t> alike(edge_count, 0);  // the neighbour runs the edge the same way
  bool any_alike = false;
  for (std::size_t edge = 0; edge < edge_count; ++edge) {
    neighbour[edge] = across[edge / 3][edge % 3];
    if (neighbour[edge] != kNoTriangle) continue;
    std::uint32_t count = 0;
    edges.others(edge, false, [&](std::uint32_t m) {
      neighbour[edge] = m / 3;
      return ++count > 1;
    });
    if (count > 1) neighbour[edge] = kNoTriangle;
    alike[edge] = neighbour[edge] != kNoTriangle;
    any_alike = any_alike || alike[edge];
  }
  if (!any_alike) return {};
  std::vector<std::uint8_t> flip(triangle_count, 0), seen(triangle_count, 0);
  std::vector<std::uint32_t> piece;
  bool any_flip = false;
  for (std::size_t seed = 0; seed < triangle_count; ++seed) {
    if (seen[seed]) continue;
    piece.assign(1, static_cast<std::uint32_t>(seed));
    seen[seed] = 1;
    double flipped_area = 0.0, kept_area = 0.0;
    std::size_t shared_edges = 0, alike_edges = 0;
    for (std::size_t i = 0; i < piece.size(); ++i) {
      const std::uint32_t t = piece[i];
      (flip[t] ? flipped_area : kept_area) += std::sqrt(dot(normal[t], normal[t]));
      for (std::size_t k = 0; k < 3; ++k) {
        const std::uint32_t other = neighbour[3 * t + k];
        if (other == kNoTriangle) continue;
        ++shared_edges;
        alike_edges += alike[3 * t + k];
        if (seen[other]) continue;
        seen[other] = 1;
        flip[other] = static_cast<std::uint8_t>(flip[t] ^ alike[3 * t + k]);
        piece.push_back(other);
      }
    }
    const bool inconsistent = alike_edges > 0 && 4 * alike_edges >= shared_edges;
    for (const std::uint32_t t : piece) flip[t] = inconsistent && (flip[t] != 0) == (kept_area >= flipped_area);
    any_flip = any_flip || inconsistent;
  }
  if (!any_flip) return {};
  return flip;
}

}  // namespace

std::uint32_t closest_triangle(const measure::TriangleBvh& bvh, const Vec3d& p) {
  return bvh.closest(glm::vec3(static_cast<float>(p[0]), static_cast<float>(p[1]), static_cast<float>(p[2]))).triangle;
}

PartBounder::PartBounder(std::span<const Triangle3d> output) : output_(output) {
  normal_.reserve(output_.size());
  for (const Triangle3d& tri : output_) normal_.push_back(cross(sub(tri[1], tri[0]), sub(tri[2], tri[0])));
  {
    const DirectedEdges edges(output_);
    across_ = triangles_across(output_.size(), edges);
    if (const std::vector<std::uint8_t> flip = rewinding(normal_, edges, across_); !flip.empty()) {
      oriented_.assign(output.begin(), output.end());
      for (std::size_t t = 0; t < flip.size(); ++t)
        if (flip[t]) {
          // corners 1 and 2 swapped: the cross product negated, to the bit
          std::swap(oriented_[t][1], oriented_[t][2]);
          normal_[t] = {-normal_[t][0], -normal_[t][1], -normal_[t][2]};
        }
      output_ = oriented_;
    }
  }
  if (!oriented_.empty()) across_ = triangles_across(output_.size(), DirectedEdges(output_));
  sphere_.reserve(output_.size());
  for (const Triangle3d& tri : output_) {
    const Sphere sphere = bounding_sphere(tri[0], tri[1], tri[2]);
    sphere_.push_back({sphere.center, sphere.radius * (1.0 + 1e-9)});
  }
}

double PartBounder::distance2(const Vec3d& p, std::uint32_t triangle) const {
  const Triangle3d& t = output_[triangle];
  return point_triangle_distance2(p, t[0], t[1], t[2]);
}

double PartBounder::nearest2(const Vec3d& p, std::span<const std::uint32_t> candidates) const {
  double best2 = kInfinity;
  for (std::uint32_t candidate : candidates) best2 = std::min(best2, distance2(p, candidate));
  return best2;
}

double PartBounder::single_bound2(const Triangle3d& part, std::span<const std::uint32_t> candidates,
                                  double settled2, const std::array<Measured, 3>* measured) const {
  double best2 = kInfinity;
  for (std::uint32_t candidate : candidates) {
    double worst2 = 0.0;
    for (std::size_t k = 0; k < 3; ++k) {
      const Vec3d& c = part[k];
      if (near_corner(c, output_[candidate], std::max(worst2, settled2))) continue;
      const bool known = measured != nullptr && (*measured)[k].triangle == candidate;
      worst2 = std::max(worst2, known ? (*measured)[k].distance2 : distance2(c, candidate));
      if (worst2 >= best2) break;
    }
    best2 = std::min(best2, worst2);
    if (best2 <= settled2) break;
  }
  return best2;
}

PartBounder::Prism::Prism(const PartBounder& bounder, const Triangle3d& part, double enough2)
    : bounder_(bounder), part_(part), enough2_(enough2) {
  // the part's plane: origin part[0], orthonormal axes x (along its first edge) and y
  const Vec3d edge0 = sub(part[1], part[0]), edge1 = sub(part[2], part[0]);
  const Vec3d n = cross(edge0, edge1);
  twice_area_ = std::sqrt(dot(n, n));
  const double length0 = std::sqrt(dot(edge0, edge0));
  if (!(twice_area_ > 0.0 && length0 > 0.0)) {
    settled_ = true;
    return;
  }
  unit_ = {n[0] / twice_area_, n[1] / twice_area_, n[2] / twice_area_};
  x_axis_ = {edge0[0] / length0, edge0[1] / length0, edge0[2] / length0};
  y_axis_ = cross(unit_, x_axis_);
  part2d_[0] = {0.0, 0.0};
  part2d_[1] = {length0, 0.0};
  part2d_[2] = {dot(edge1, x_axis_), dot(edge1, y_axis_)};
  // the part's bounding sphere (around its centroid): a candidate whose sphere is farther from
  // it across the normal than both radii cannot reach under it
  middle_ = centroid(part[0], part[1], part[2]);
  double radius2 = 0.0;
  for (const Vec3d& c : part) {
    const Vec3d d = sub(c, middle_);
    radius2 = std::max(radius2, dot(d, d));
  }
  radius_ = std::sqrt(radius2);
}

bool PartBounder::Prism::offer(std::uint32_t candidate) {
  if (settled_) return true;
  // offered before: only a piece or a candidate facing away is remembered (the others are
  // passed over again as they were)
  if (holds(piece_triangle_, piece_count_, candidate) | holds(facing_away_, facing_away_count_, candidate))
    return false;
  const Sphere& sphere = bounder_.sphere_[candidate];
  const Vec3d apart = sub(sphere.center, middle_);
  const double across2 = dot(apart, apart) - dot(apart, unit_) * dot(apart, unit_);
  const double reach = radius_ + sphere.radius;
  if (across2 > reach * reach) return false;
  const Triangle3d& tri = bounder_.output_[candidate];
  const Vec3d& normal = bounder_.normal_[candidate];
  const double facing = dot(normal, unit_);
  if (!(facing > 0.0)) {  // faces away (kept for the reversed part: bound2), or stands on edge: its prism is flat
    if (facing < 0.0 && facing_away_count_ < kMaxPieces) facing_away_[facing_away_count_++] = candidate;
    return false;
  }
  Point2 corner[3];
  for (std::size_t j = 0; j < 3; ++j) {
    const Vec3d r = sub(tri[j], part_[0]);
    corner[j] = {dot(r, x_axis_), dot(r, y_axis_)};
  }
  // the part against the prism's sides (the projected triangle winds counter-clockwise);
  // left_of values this small are rounding: a millionth of a millionth of their scale
  const double on_line = 1e-12 * reach * reach;
  // (the sides' signs combined with & and |, not && and ||: each is a coin toss per candidate,
  // and a branch per comparison mispredicted more than the comparisons cost)
  std::array<std::array<double, 9>, 3> side;  // of the part's corners: the first clip's sides
  std::array<bool, 3> cuts{};  // per prism side: its line cuts into the part
  bool empty = false, inside = true;
  for (std::size_t e = 0; e < 3 && !empty; ++e) {
    const Point2 &from = corner[e], &to = corner[e + 1 == 3 ? 0 : e + 1];
    for (std::size_t k = 0; k < 3; ++k) side[e][k] = side_of(from, to, part2d_[k], on_line);
    empty = (side[e][0] < 0.0) & (side[e][1] < 0.0) & (side[e][2] < 0.0);
    cuts[e] = (side[e][0] < 0.0) | (side[e][1] < 0.0) | (side[e][2] < 0.0);
    inside = inside & (side[e][0] >= 0.0) & (side[e][1] >= 0.0) & (side[e][2] >= 0.0);
  }
  if (empty) return false;
  // clipped by the sides whose lines cut into the part (the others keep all of it, and a piece
  // side along them can only be the part's own); corner k of the part lies on its sides k - 1 and k.
  // Each clip writes the other polygon.
  Polygon polygons[2];  // only the corners in use written: zeroing all nine was 6% of this function's time
  Polygon* piece = &polygons[0];
  piece->corner[0] = part2d_[0], piece->corner[1] = part2d_[1], piece->corner[2] = part2d_[2];
  piece->on[0] = kPartSide2 | kPartSide0, piece->on[1] = kPartSide0 | kPartSide1, piece->on[2] = kPartSide1 | kPartSide2;
  piece->size = 3;
  bool clipped = false;
  for (std::size_t e = 0; e < 3 && !inside && piece->size > 0; ++e) {
    if (!cuts[e]) continue;
    if (clipped) {
      const Point2 &from = corner[e], &to = corner[e + 1 == 3 ? 0 : e + 1];
      for (std::size_t k = 0; k < piece->size; ++k) side[e][k] = side_of(from, to, piece->corner[k], on_line);
    }
    Polygon* kept = piece == &polygons[0] ? &polygons[1] : &polygons[0];
    clip(*piece, side[e], e, *kept);
    piece = kept;
    clipped = true;
  }
  const Polygon& cut = *piece;
  if (cut.size < 3) return false;
  if (piece_count_ == kMaxPieces) {  // never seen: a part lies over a few output triangles
    settled_ = true;
    return true;
  }
  unsigned open = 0;
  for (std::size_t k = 0; k < cut.size; ++k) {
    const unsigned along = cut.on[k] & cut.on[k + 1 == cut.size ? 0 : k + 1];
    if ((along & kPartSides) == 0) open |= along;
  }
  piece_triangle_[piece_count_] = candidate;
  piece_open_[piece_count_++] = open;
  for (std::size_t k = 1; k + 1 < cut.size; ++k) covered_ += left_of(cut.corner[0], cut.corner[k], cut.corner[k + 1]);
  // distance along the part's normal to the candidate's plane: affine in the plane's coordinates
  const double along0 = dot(sub(part_[0], tri[0]), normal) / facing;
  const double along_x = dot(x_axis_, normal) / facing, along_y = dot(y_axis_, normal) / facing;
  for (std::size_t k = 0; k < cut.size; ++k) {
    const Point2& q = cut.corner[k];
    const double along = along0 + q[0] * along_x + q[1] * along_y;
    if (along * along <= enough2_) {
      worst2_ = std::max(worst2_, along * along);
      continue;
    }
    const Vec3d x{part_[0][0] + q[0] * x_axis_[0] + q[1] * y_axis_[0], part_[0][1] + q[0] * x_axis_[1] + q[1] * y_axis_[1],
                  part_[0][2] + q[0] * x_axis_[2] + q[1] * y_axis_[2]};
    worst2_ = std::max(worst2_, bounder_.distance2(x, candidate));
  }
  // the areas add up: the pieces so far cover the part or nothing will (the candidates after
  // them could only overlap)
  if (std::abs(covered_ - twice_area_) > kCoverTolerance * twice_area_) return false;
  settled_ = true;
  covers_ = closed();
  return true;
}

bool PartBounder::Prism::offer_neighbours() {
  // piece_count_ grows as the pieces are offered: their own open sides are walked in turn
  for (std::size_t i = 0; i < piece_count_ && !settled_; ++i)
    for (unsigned open = piece_open_[i]; open != 0; open &= open - 1) {
      const std::uint32_t across = bounder_.across_[piece_triangle_[i]][std::countr_zero(open)];
      if (across != kNoTriangle && offer(across)) return true;
    }
  return settled_;
}

// The areas alone could add up with an overlap (a fold) cancelling a gap. Every piece side along
// a prism side inside the part has the output triangle across that edge (facing like the part, so
// its projection lies on the other side) among the pieces: the pieces' union has no border inside
// the part, so it covers it, and with the areas adding up they do not overlap. (The triangle
// across: one that runs the edge the other way, found by position, so that attribute seams and
// two-sided sheets do not hide it.)
bool PartBounder::Prism::closed() const {
  const auto& output = bounder_.output_;
  for (std::size_t i = 0; i < piece_count_; ++i)
    for (unsigned open = piece_open_[i]; open != 0; open &= open - 1) {
      const auto e = static_cast<std::size_t>(std::countr_zero(open));
      const std::uint32_t of = piece_triangle_[i];
      // the first triangle across is a piece at all but 1 in 8,000 open sides (200K rock); else
      // any other piece that runs the edge backwards (kNoTriangle is none)
      if (holds(piece_triangle_, piece_count_, bounder_.across_[of][e])) continue;
      const Vec3d &from = output[of][e + 1 == 3 ? 0 : e + 1], &to = output[of][e];
      bool across = false;
      for (std::size_t j = 0; j < piece_count_ && !across; ++j) {
        const Triangle3d& t = output[piece_triangle_[j]];
        for (std::size_t k = 0; k < 3 && !across; ++k) across = j != i && t[k] == from && t[k + 1 == 3 ? 0 : k + 1] == to;
      }
      if (!across) return false;
    }
  return true;
}

double PartBounder::Prism::bound2() const {
  if (covers_) return worst2_;
  if (facing_away_count_ == 0 || twice_area_ == 0.0) return std::numeric_limits<double>::infinity();
  // The part wound the other way, over the candidates that face away from it: where the output
  // or the input is wound inconsistently, these are the ones that lie along it.
  const Triangle3d reversed{part_[0], part_[2], part_[1]};
  Prism back(bounder_, reversed, enough2_);
  for (std::size_t i = 0; i < facing_away_count_; ++i)
    if (back.offer(facing_away_[i])) break;
  return back.covers_ ? back.worst2_ : std::numeric_limits<double>::infinity();
}

double PartBounder::prism_bound2(const Triangle3d& part, std::span<const std::uint32_t> candidates,
                                 double enough2) const {
  Prism prism(*this, part, enough2);
  for (std::uint32_t candidate : candidates)
    if (prism.offer(candidate)) break;
  return prism.bound2();
}

double PartBounder::bound2(const Triangle3d& part, std::span<const std::uint32_t> candidates, double enough2,
                           const measure::TriangleBvh* queries, int depth) const {
  const Vec3d middle = centroid(part[0], part[1], part[2]);
  std::vector<std::uint32_t> extended;
  if (depth == 0) candidates = with_nearest(candidates, std::array<Vec3d, 4>{part[0], part[1], part[2], middle}, queries, extended);
  else candidates = with_nearest(candidates, std::array<Vec3d, 1>{middle}, queries, extended);
  return split_bound2(part, candidates, prism_bound2(part, candidates, enough2), enough2, queries, depth);
}

double PartBounder::split_bound2(const Triangle3d& part, std::span<const std::uint32_t> candidates, double prism2,
                                 double enough2, const measure::TriangleBvh* queries, int depth) const {
  if (prism2 <= enough2) return prism2;
  const double single2 = std::min(prism2, single_bound2(part, candidates));
  if (depth >= kMaxRefineDepth || single2 <= enough2) return single2;
  const double lower2 = std::max({nearest2(part[0], candidates), nearest2(part[1], candidates), nearest2(part[2], candidates)});
  if (single2 <= lower2 * kCloseEnough2) return single2;
  const Triangle3d mid{midpoint(part[0], part[1]), midpoint(part[1], part[2]), midpoint(part[2], part[0])};
  std::vector<std::uint32_t> extended;
  candidates = with_nearest(candidates, mid, queries, extended);
  const std::array<Triangle3d, 4> parts{
      {{part[0], mid[0], mid[2]}, {mid[0], part[1], mid[1]}, {mid[2], mid[1], part[2]}, {mid[0], mid[1], mid[2]}}};
  double result2 = 0.0;
  for (const Triangle3d& piece : parts)
    result2 = std::max(result2, bound2(piece, candidates, std::max(enough2, result2), queries, depth + 1));
  return std::min(result2, single2);
}

}  // namespace octolod::bake
