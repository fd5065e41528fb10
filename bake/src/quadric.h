// Generalized quadric error metrics in R^n (Garland & Heckbert 1998, "Simplifying surfaces with
// color and texture using quadric error metrics", section 3; seed 3.5, 4.4). A vertex is a point
// v in R^n: position x,y,z followed by its attribute floats (normal +3, colour +3, uv +2, in
// VertexLayout order), so n is 3..11. For a triangle T = (p,q,r) in R^n:
//   e1 = (q-p)/|q-p|,  e2 = (r-p-(e1.(r-p))e1)/|...|        orthonormal basis of T's plane
//   A  = I - e1 e1^T - e2 e2^T,  b = (p.e1)e1 + (p.e2)e2 - p,  c = p.p - (p.e1)^2 - (p.e2)^2
// and Q(v) = v^T A v + 2 b^T v + c is the squared distance from v to the plane of T in R^n. With
// n = 3 it is the classic plane quadric (Garland & Heckbert 1997) of the position alone.
// Quadrics are weighted by the triangle's area in 3D (attributes do not change the weight) and
// summed in double precision. Callers translate positions to a local origin (the node's cell
// centre) first: c = p.p - ... cancels catastrophically far from the origin.
//
// Storage: a quadric of dimension n is quadric_floats(n) doubles: A's upper triangle packed row by
// row (n(n+1)/2), then b (n), then c. Sums are plain element-wise additions.
#pragma once

#include <array>
#include <cstddef>

namespace octolod::bake {

inline constexpr int kMaxQuadricDim = 11;

constexpr std::size_t quadric_doubles(int n) {
  return static_cast<std::size_t>(n * (n + 1) / 2 + n + 1);
}
inline constexpr std::size_t kMaxQuadricDoubles = quadric_doubles(kMaxQuadricDim);

// Writes weight * (A, b, c) of the triangle (p,q,r) in R^n into `out` (quadric_doubles(n)).
// A triangle that is degenerate in R^n (coincident or collinear corners) writes zeros, as does
// weight 0.
void triangle_quadric(int n, const double* p, const double* q, const double* r, double weight,
                      double* out);

// The n = 3 quadric of the plane through p (3 values) with normal `normal` (any length), times
// weight: the same quadric as triangle_quadric(3, ...) of a triangle with that plane, from a
// normal the caller already has (a cross product of two edges) instead of an orthonormal basis.
// A zero normal, or weight 0, writes zeros.
void plane_quadric(const double* normal, const double* p, double weight, double* out);

// acc += q, both of dimension n.
inline void add_quadric(int n, double* acc, const double* q) {
  const std::size_t count = quadric_doubles(n);
  for (std::size_t i = 0; i < count; ++i) acc[i] += q[i];
}

// Q(v) = v^T A v + 2 b^T v + c.
double evaluate_quadric(int n, const double* q, const double* v);

// The eigen-decomposition of a symmetric 3 x 3 matrix given by its upper triangle (xx, xy, xz,
// yy, yz, zz): eigenvalues from the largest down, each with its unit eigenvector. Deterministic
// (cyclic Jacobi); equal eigenvalues in the order the sweeps leave them.
struct Eigen3 {
  std::array<double, 3> value;
  std::array<std::array<double, 3>, 3> vector;
};
Eigen3 symmetric_eigen3(const std::array<double, 6>& upper);

// Relative eigenvalue threshold of the pseudo-inverse: eigen-directions of A whose eigenvalue is
// below this fraction of the largest are treated as unconstrained (Lindstrom 2000 uses 1e-3 for
// the same purpose), so nearly flat clusters keep their representative near the mean instead of
// sliding far along a weakly curved direction.
inline constexpr double kPseudoInverseThreshold = 1e-3;

// The minimizer of Q nearest to `mean` (both R^n): v = mean + A^+ (-b - A mean), A^+ the
// pseudo-inverse from a symmetric eigen-decomposition with kPseudoInverseThreshold (or, when
// every LDL^T pivot of A exceeds that threshold times A's largest diagonal entry, the unique
// minimizer by the factorization, several times cheaper). Exactly
// `mean` when A is zero (no triangles).
void minimize_quadric(int n, const double* q, const double* mean, double* v);

// Minimizes Q over the coordinates k..n-1 with v[0..k) fixed (e.g. the attributes of a wedge
// with its position fixed, k = 3): solves A_ff v_f = -(b_f + A_fx v_x) by pseudo-inverse, the
// solution nearest to mean_free (n-k values) in the null space. Writes v[k..n).
void minimize_quadric_free_tail(int n, int k, const double* q, const double* mean_free,
                                double* v);

// What minimize_quadric_free_tail needs of a quadric once v[0..k) is known: A_ff's upper
// triangle packed row by row ((n-k)(n-k+1)/2), then b_f + A_fx v_x (n-k). Sums of quadrics give
// sums of blocks for the same v_x, so a wedge whose position is solved first accumulates
// free_block_doubles(n - k) doubles per triangle instead of quadric_doubles(n) (44 instead of 78
// with every attribute).
constexpr std::size_t free_block_doubles(int m) { return static_cast<std::size_t>(m * (m + 1) / 2 + m); }
// acc += the free block of q (dimension n) with the first k coordinates fixed at x.
void add_free_block(int n, int k, const double* q, const double* x, double* acc);
// A triangle's quadric as the attribute solves of a clustering need it, with the position
// (coordinates 0..2) fixed per corner: add_triangle_free_block(part, x, acc) adds exactly what
// triangle_quadric(n, p, q, r, weight) followed by add_free_block(n, 3, ..., x, acc) adds (up to
// rounding), without forming the quadric's position rows, once per solved corner.
struct TriangleFreePart {
  int n = 0;
  double weight = 0.0;
  double e1[kMaxQuadricDim];  // the orthonormal basis of the triangle's plane in R^n
  double e2[kMaxQuadricDim];
  double pe1 = 0.0, pe2 = 0.0;                          // p . e1, p . e2
  double p_free[kMaxQuadricDim - 3];                    // p's attribute coordinates
  // weight (I - e1 e1^T - e2 e2^T): its attribute rows from the diagonal, packed
  double a_ff[(kMaxQuadricDim - 3) * (kMaxQuadricDim - 2) / 2];
};
// Fills `part` for the triangle (p, q, r) in R^n (n = 4..11); false (nothing to add) where
// triangle_quadric writes zeros: weight 0 or a degenerate triangle in R^n.
bool triangle_free_part(int n, const double* p, const double* q, const double* r, double weight,
                        TriangleFreePart& part);
// acc (free_block_doubles(n - 3) doubles) += the part's free block with the position fixed at x.
void add_triangle_free_block(const TriangleFreePart& part, const double* x, double* acc);
// minimize_quadric_free_tail from a free block of m = n - k coordinates: writes the m free ones.
void minimize_free_block(int m, const double* block, const double* mean_free, double* free);

}  // namespace octolod::bake
