// Generalized quadrics (Garland & Heckbert 1998, section 3) and their robust minimization by a
// symmetric eigen-decomposition (cyclic Jacobi, Golub & Van Loan 8.5) and pseudo-inverse.
#include "quadric.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <type_traits>

namespace octolod::bake {
namespace {

using Matrix = std::array<double, kMaxQuadricDim * kMaxQuadricDim>;
using Vector = std::array<double, kMaxQuadricDim>;

std::size_t packed_index(int n, int i, int j) {  // i <= j
  return static_cast<std::size_t>(i * n - i * (i - 1) / 2 + (j - i));
}

// Calls f(std::integral_constant<int, m>{}) for the run-time dimension m (1..kMaxQuadricDim):
// a size known at compile time lets the loops of the hot kernels unroll and vectorize.
template <typename F>
decltype(auto) with_fixed_dimension(int m, F&& f) {
  static_assert(kMaxQuadricDim == 11, "one case per dimension below kMaxQuadricDim");
  switch (m) {
    case 1: return f(std::integral_constant<int, 1>{});
    case 2: return f(std::integral_constant<int, 2>{});
    case 3: return f(std::integral_constant<int, 3>{});
    case 4: return f(std::integral_constant<int, 4>{});
    case 5: return f(std::integral_constant<int, 5>{});
    case 6: return f(std::integral_constant<int, 6>{});
    case 7: return f(std::integral_constant<int, 7>{});
    case 8: return f(std::integral_constant<int, 8>{});
    case 9: return f(std::integral_constant<int, 9>{});
    case 10: return f(std::integral_constant<int, 10>{});
    default: return f(std::integral_constant<int, kMaxQuadricDim>{});
  }
}

double dot(int n, const double* x, const double* y) {
  double s = 0.0;
  for (int i = 0; i < n; ++i) s += x[i] * y[i];
  return s;
}

// Eigen-decomposition of the symmetric m x m matrix `a` (row-major, stride kMaxQuadricDim; its
// content is destroyed): eigenvalues in `values`, eigenvectors as the COLUMNS of `vectors`.
void symmetric_eigen(int m, Matrix& a, Vector& values, Matrix& vectors) {
  constexpr int s = kMaxQuadricDim;
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < m; ++j) vectors[static_cast<std::size_t>(i * s + j)] = i == j ? 1.0 : 0.0;
  auto at = [&a](int i, int j) -> double& { return a[static_cast<std::size_t>(i * s + j)]; };
  auto vec = [&vectors](int i, int j) -> double& {
    return vectors[static_cast<std::size_t>(i * s + j)];
  };
  for (int sweep = 0; sweep < 50; ++sweep) {
    double off = 0.0, diag = 0.0;
    for (int i = 0; i < m; ++i) {
      diag += at(i, i) * at(i, i);
      for (int j = i + 1; j < m; ++j) off += at(i, j) * at(i, j);
    }
    if (off <= 1e-30 * diag || off == 0.0) break;
    for (int p = 0; p < m; ++p) {
      for (int q = p + 1; q < m; ++q) {
        const double apq = at(p, q);
        if (apq == 0.0) continue;
        const double theta = (at(q, q) - at(p, p)) / (2.0 * apq);
        const double t = (theta >= 0 ? 1.0 : -1.0) / (std::fabs(theta) + std::sqrt(theta * theta + 1.0));
        const double c = 1.0 / std::sqrt(t * t + 1.0);
        const double sn = t * c;
        for (int k = 0; k < m; ++k) {  // columns p, q
          const double akp = at(k, p), akq = at(k, q);
          at(k, p) = c * akp - sn * akq;
          at(k, q) = sn * akp + c * akq;
        }
        for (int k = 0; k < m; ++k) {  // rows p, q
          const double apk = at(p, k), aqk = at(q, k);
          at(p, k) = c * apk - sn * aqk;
          at(q, k) = sn * apk + c * aqk;
        }
        for (int k = 0; k < m; ++k) {
          const double vkp = vec(k, p), vkq = vec(k, q);
          vec(k, p) = c * vkp - sn * vkq;
          vec(k, q) = sn * vkp + c * vkq;
        }
      }
    }
  }
  for (int i = 0; i < m; ++i) values[static_cast<std::size_t>(i)] = at(i, i);
}

// Solves M x = rhs by an LDL^T factorization, M symmetric m x m given by its upper triangle
// packed row by row and rhs by minus the m values after it, as a free block holds them
// (quadric.h), when every pivot exceeds kPseudoInverseThreshold times the largest diagonal
// entry, i.e. when M is comfortably full rank; false (x untouched) otherwise. The fast path of
// minimize_free_block: the attribute blocks of generalized quadrics are nearly always well
// conditioned (99.4% of the 4.8M solves of a 1M city bake), and a factorization costs a small
// fraction of an eigen-decomposition.
// Read from the packed block, with m known at compile time: the same arithmetic after copies
// into an 11 x 11 matrix and a right-hand side took 170 ns instead of 127 for m = 8 (every
// attribute), 31 instead of 9 for m = 3 (bench/cluster_bench).
template <int m>
bool solve_packed_well_conditioned(const double* packed, double* x) {
  // packed row i holds M[i][i..m): M[i][j] (i <= j) at row_start[i] + j - i
  constexpr auto row_start = [] {
    std::array<int, m> start{};
    for (int i = 1; i < m; ++i) start[static_cast<std::size_t>(i)] = start[static_cast<std::size_t>(i - 1)] + m - (i - 1);
    return start;
  }();
  auto entry = [&](int i, int j) { return packed[row_start[static_cast<std::size_t>(i)] + j - i]; };  // i <= j
  double largest = 0.0;
  for (int i = 0; i < m; ++i) largest = std::max(largest, entry(i, i));
  if (!(largest > 0.0)) return false;
  const double threshold = kPseudoInverseThreshold * largest;
  std::array<double, m * m> l;  // (only the entries written below are read) unit lower triangle below the diagonal, D on the diagonal
  auto at = [&l](int i, int j) -> double& { return l[static_cast<std::size_t>(i * m + j)]; };
  std::array<double, m> ld{};  // row j of L times D: ld[k] = L_jk D_k, one multiplication per update below
  for (int j = 0; j < m; ++j) {
    double d = entry(j, j);
    for (int k = 0; k < j; ++k) {
      ld[static_cast<std::size_t>(k)] = at(j, k) * at(k, k);
      d -= at(j, k) * ld[static_cast<std::size_t>(k)];
    }
    if (!(d > threshold)) return false;
    at(j, j) = d;
    for (int i = j + 1; i < m; ++i) {
      double v = entry(j, i);
      for (int k = 0; k < j; ++k) v -= at(i, k) * ld[static_cast<std::size_t>(k)];
      at(i, j) = v / d;
    }
  }
  std::array<double, m> y{};
  const double* tail = packed + m * (m + 1) / 2;
  for (int i = 0; i < m; ++i) {  // L y = rhs
    double v = -tail[i];
    for (int k = 0; k < i; ++k) v -= at(i, k) * y[static_cast<std::size_t>(k)];
    y[static_cast<std::size_t>(i)] = v;
  }
  for (int i = 0; i < m; ++i) y[static_cast<std::size_t>(i)] /= at(i, i);  // D z = y
  for (int i = m; i-- > 0;) {  // L^T x = z
    double v = y[static_cast<std::size_t>(i)];
    for (int k = i + 1; k < m; ++k) v -= at(k, i) * x[k];
    x[i] = v;
  }
  return true;
}

// x = x0 + M^+ (rhs - M x0) for the symmetric m x m matrix M (row-major, stride
// kMaxQuadricDim, destroyed): the solution of M x = rhs (least squares) nearest x0.
void solve_nearest(int m, Matrix& mat, const double* rhs, const double* x0, double* x) {
  constexpr int s = kMaxQuadricDim;
  Vector residual{};
  for (int i = 0; i < m; ++i) {
    double r = rhs[i];
    for (int j = 0; j < m; ++j) r -= mat[static_cast<std::size_t>(i * s + j)] * x0[j];
    residual[static_cast<std::size_t>(i)] = r;
  }
  Vector values{};
  Matrix vectors;  // written by symmetric_eigen
  symmetric_eigen(m, mat, values, vectors);
  double largest = 0.0;
  for (int i = 0; i < m; ++i) largest = std::max(largest, std::fabs(values[static_cast<std::size_t>(i)]));
  for (int i = 0; i < m; ++i) x[i] = x0[i];
  if (largest == 0.0) return;
  const double threshold = kPseudoInverseThreshold * largest;
  for (int e = 0; e < m; ++e) {
    const double lambda = values[static_cast<std::size_t>(e)];
    if (std::fabs(lambda) <= threshold) continue;
    double projection = 0.0;
    for (int i = 0; i < m; ++i)
      projection += vectors[static_cast<std::size_t>(i * s + e)] * residual[static_cast<std::size_t>(i)];
    const double scale = projection / lambda;
    for (int i = 0; i < m; ++i) x[i] += scale * vectors[static_cast<std::size_t>(i * s + e)];
  }
}

}  // namespace

Eigen3 symmetric_eigen3(const std::array<double, 6>& upper) {
  constexpr int s = kMaxQuadricDim;
  Matrix a{};
  const int index[3][3] = {{0, 1, 2}, {1, 3, 4}, {2, 4, 5}};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) a[static_cast<std::size_t>(i * s + j)] = upper[static_cast<std::size_t>(index[i][j])];
  Vector values{};
  Matrix vectors{};
  symmetric_eigen(3, a, values, vectors);
  std::array<int, 3> order = {0, 1, 2};
  std::stable_sort(order.begin(), order.end(), [&values](int x, int y) { return values[x] > values[y]; });
  Eigen3 eigen{};
  for (std::size_t k = 0; k < 3; ++k) {
    eigen.value[k] = values[static_cast<std::size_t>(order[k])];
    for (std::size_t i = 0; i < 3; ++i) eigen.vector[k][i] = vectors[i * s + static_cast<std::size_t>(order[k])];
  }
  return eigen;
}

namespace {

// The orthonormal basis (e1, e2) of the plane of the triangle (p, q, r) in R^n (quadric.h);
// false when the triangle is degenerate in R^n (coincident or collinear corners).
template <int n>
bool plane_basis(const double* p, const double* q, const double* r, double* e1, double* e2) {
  for (int i = 0; i < n; ++i) e1[i] = q[i] - p[i];
  const double len1 = std::sqrt(dot(n, e1, e1));
  if (!(len1 > 0.0)) return false;
  for (int i = 0; i < n; ++i) e1[i] /= len1;
  Vector rp{};
  for (int i = 0; i < n; ++i) rp[static_cast<std::size_t>(i)] = r[i] - p[i];
  const double along = dot(n, e1, rp.data());
  for (int i = 0; i < n; ++i) e2[i] = rp[static_cast<std::size_t>(i)] - along * e1[i];
  const double len2 = std::sqrt(dot(n, e2, e2));
  // Collinear in R^n: no plane. Relative test, so tiny well-shaped triangles still count.
  if (!(len2 > 1e-12 * len1)) return false;
  for (int i = 0; i < n; ++i) e2[i] /= len2;
  return true;
}

// triangle_quadric for a dimension known at compile time: the loops unroll and vectorize.
template <int n>
void triangle_quadric_fixed(const double* p, const double* q, const double* r, double weight, double* out) {
  constexpr std::size_t count = quadric_doubles(n);
  Vector e1{}, e2{};
  if (weight <= 0.0 || !plane_basis<n>(p, q, r, e1.data(), e2.data())) {
    std::fill(out, out + count, 0.0);
    return;
  }
  double* a = out;  // packed upper triangle, row by row
  for (int i = 0; i < n; ++i) {
    const double w1 = weight * e1[static_cast<std::size_t>(i)], w2 = weight * e2[static_cast<std::size_t>(i)];
    *a++ = weight - w1 * e1[static_cast<std::size_t>(i)] - w2 * e2[static_cast<std::size_t>(i)];
    for (int j = i + 1; j < n; ++j) *a++ = -w1 * e1[static_cast<std::size_t>(j)] - w2 * e2[static_cast<std::size_t>(j)];
  }
  double* b = out + n * (n + 1) / 2;
  const double pe1 = dot(n, p, e1.data());
  const double pe2 = dot(n, p, e2.data());
  for (int i = 0; i < n; ++i) {
    const auto ui = static_cast<std::size_t>(i);
    b[i] = weight * (pe1 * e1[ui] + pe2 * e2[ui] - p[i]);
  }
  out[count - 1] = weight * (dot(n, p, p) - pe1 * pe1 - pe2 * pe2);
}

// triangle_free_part for a dimension known at compile time.
template <int n>
bool triangle_free_part_fixed(const double* p, const double* q, const double* r, double weight, TriangleFreePart& part) {
  if (weight <= 0.0 || !plane_basis<n>(p, q, r, part.e1, part.e2)) return false;
  constexpr int m = n - 3;
  part.n = n;
  part.weight = weight;
  part.pe1 = dot(n, p, part.e1);
  part.pe2 = dot(n, p, part.e2);
  for (int i = 0; i < m; ++i) part.p_free[i] = p[3 + i];
  double* a = part.a_ff;  // A's rows 3..n-1 from the diagonal: weight (I - e1 e1^T - e2 e2^T)
  for (int i = 3; i < n; ++i) {
    const double w1 = weight * part.e1[i], w2 = weight * part.e2[i];
    *a++ = weight - w1 * part.e1[i] - w2 * part.e2[i];
    for (int j = i + 1; j < n; ++j) *a++ = -w1 * part.e1[j] - w2 * part.e2[j];
  }
  return true;
}

template <int n>
void add_triangle_free_block_fixed(const TriangleFreePart& part, const double* x, double* acc) {
  constexpr int m = n - 3;
  constexpr int ff = m * (m + 1) / 2;
  for (int i = 0; i < ff; ++i) acc[i] += part.a_ff[i];
  // b_f + A_fx x = weight ((p.e1 - e1_x.x) e1_f + (p.e2 - e2_x.x) e2_f - p_f): A's identity part
  // has no position-attribute entries
  const double s1 = part.pe1 - (part.e1[0] * x[0] + part.e1[1] * x[1] + part.e1[2] * x[2]);
  const double s2 = part.pe2 - (part.e2[0] * x[0] + part.e2[1] * x[1] + part.e2[2] * x[2]);
  double* rhs = acc + ff;
  for (int i = 0; i < m; ++i) rhs[i] += part.weight * (s1 * part.e1[3 + i] + s2 * part.e2[3 + i] - part.p_free[i]);
}

}  // namespace

bool triangle_free_part(int n, const double* p, const double* q, const double* r, double weight,
                        TriangleFreePart& part) {
  assert(n > 3 && n <= kMaxQuadricDim && "a free part needs attributes (n = 4..11)");
  return with_fixed_dimension(n, [&](auto fixed) {
    constexpr int dimension = decltype(fixed)::value;
    if constexpr (dimension > 3) return triangle_free_part_fixed<dimension>(p, q, r, weight, part);
    else return false;
  });
}

void add_triangle_free_block(const TriangleFreePart& part, const double* x, double* acc) {
  with_fixed_dimension(part.n, [&](auto fixed) {
    constexpr int dimension = decltype(fixed)::value;
    if constexpr (dimension > 3) add_triangle_free_block_fixed<dimension>(part, x, acc);
  });
}

void triangle_quadric(int n, const double* p, const double* q, const double* r, double weight,
                      double* out) {
  assert(n >= 3 && n <= kMaxQuadricDim && "quadric dimension must be 3..11");
  with_fixed_dimension(n, [&](auto fixed) {
    triangle_quadric_fixed<decltype(fixed)::value>(p, q, r, weight, out);
  });
}

void plane_quadric(const double* normal, const double* p, double weight, double* out) {
  const double len2 = normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2];
  if (!(len2 > 0.0) || weight <= 0.0) {
    std::fill(out, out + quadric_doubles(3), 0.0);
    return;
  }
  const double scale = weight / len2;  // A = weight * n n^T / |n|^2
  const double d = -(normal[0] * p[0] + normal[1] * p[1] + normal[2] * p[2]);  // plane: n.x + d = 0
  out[0] = scale * normal[0] * normal[0];
  out[1] = scale * normal[0] * normal[1];
  out[2] = scale * normal[0] * normal[2];
  out[3] = scale * normal[1] * normal[1];
  out[4] = scale * normal[1] * normal[2];
  out[5] = scale * normal[2] * normal[2];
  for (int i = 0; i < 3; ++i) out[6 + i] = scale * d * normal[i];
  out[9] = scale * d * d;
}

double evaluate_quadric(int n, const double* q, const double* v) {
  double s = 0.0;
  for (int i = 0; i < n; ++i) {
    s += q[packed_index(n, i, i)] * v[i] * v[i];
    for (int j = i + 1; j < n; ++j) s += 2.0 * q[packed_index(n, i, j)] * v[i] * v[j];
  }
  const double* b = q + n * (n + 1) / 2;
  s += 2.0 * dot(n, b, v);
  return s + q[quadric_doubles(n) - 1];
}

void minimize_quadric(int n, const double* q, const double* mean, double* v) {
  minimize_quadric_free_tail(n, 0, q, mean, v);
}

namespace {

// add_free_block for a dimension known at compile time: the loops unroll.
template <int n>
void add_free_block_fixed(int k, const double* q, const double* x, double* acc) {
  const int m = n - k;
  const int ff = m * (m + 1) / 2;
  // A's packed rows k..n-1 hold exactly A_ff, packed the same way, after the k rows before them
  const double* a_ff = q + (k * n - k * (k - 1) / 2);
  for (int i = 0; i < ff; ++i) acc[i] += a_ff[i];
  double* rhs = acc + ff;  // b_f + A_fx x
  const double* b = q + n * (n + 1) / 2;
  for (int i = 0; i < m; ++i) rhs[i] += b[k + i];
  const double* row = q;  // packed row r of A: A[r][r..n)
  for (int r = 0; r < k; ++r) {
    for (int i = 0; i < m; ++i) rhs[i] += row[k - r + i] * x[r];  // A_xf = A_fx^T
    row += n - r;
  }
}

}  // namespace

void add_free_block(int n, int k, const double* q, const double* x, double* acc) {
  assert(k >= 0 && k < n && n <= kMaxQuadricDim && "free coordinates k..n-1 must be non-empty");
  with_fixed_dimension(n, [&](auto fixed) { add_free_block_fixed<decltype(fixed)::value>(k, q, x, acc); });
}

void minimize_free_block(int m, const double* block, const double* mean_free, double* free) {
  assert(m >= 1 && m <= kMaxQuadricDim && "free coordinates must be 1..kMaxQuadricDim");
  const bool solved = with_fixed_dimension(m, [&](auto fixed) {
    return solve_packed_well_conditioned<decltype(fixed)::value>(block, free);
  });
  if (solved) return;
  const double* tail = block + m * (m + 1) / 2;  // b_f + A_fx v_x
  Vector rhs{};
  for (int i = 0; i < m; ++i) rhs[static_cast<std::size_t>(i)] = -tail[i];
  Matrix mat;  // only its m x m block, written below, is read
  const double* row = block;
  for (int i = 0; i < m; ++i) {
    for (int j = i; j < m; ++j) {
      mat[static_cast<std::size_t>(i * kMaxQuadricDim + j)] = row[j - i];
      mat[static_cast<std::size_t>(j * kMaxQuadricDim + i)] = row[j - i];
    }
    row += m - i;
  }
  solve_nearest(m, mat, rhs.data(), mean_free, free);
}

void minimize_quadric_free_tail(int n, int k, const double* q, const double* mean_free,
                                double* v) {
  double block[free_block_doubles(kMaxQuadricDim)] = {};
  add_free_block(n, k, q, v, block);
  minimize_free_block(n - k, block, mean_free, v + k);
}

}  // namespace octolod::bake
