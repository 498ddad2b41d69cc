#include "common/knot/invariants.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cstdlib>
#include <queue>
#include <utility>

#include "common/base/check.h"

namespace microdex::knot {
namespace {

// GCC/Clang 128-bit integers (exact products of 61-bit residues, Bareiss minors).
__extension__ using Int128 = __int128;
__extension__ using UInt128 = unsigned __int128;

// ---- Arithmetic modulo the Mersenne prime 2^61 - 1 (exact determinants). ----
constexpr std::uint64_t kPrime = (std::uint64_t{1} << 61) - 1;

std::uint64_t MulMod(std::uint64_t a, std::uint64_t b) {
  const UInt128 p = static_cast<UInt128>(a) * b;
  std::uint64_t lo = static_cast<std::uint64_t>(p & kPrime);
  std::uint64_t hi = static_cast<std::uint64_t>(p >> 61);
  std::uint64_t s = lo + hi;
  return s >= kPrime ? s - kPrime : s;
}
std::uint64_t AddMod(std::uint64_t a, std::uint64_t b) {
  const std::uint64_t s = a + b;
  return s >= kPrime ? s - kPrime : s;
}
std::uint64_t SubMod(std::uint64_t a, std::uint64_t b) { return a >= b ? a - b : a + kPrime - b; }
std::uint64_t FromSigned(std::int64_t v) {
  const std::int64_t r = v % static_cast<std::int64_t>(kPrime);
  return static_cast<std::uint64_t>(r < 0 ? r + static_cast<std::int64_t>(kPrime) : r);
}
std::int64_t ToSigned(std::uint64_t v) {
  return v > kPrime / 2 ? -static_cast<std::int64_t>(kPrime - v) : static_cast<std::int64_t>(v);
}
std::uint64_t PowMod(std::uint64_t a, std::uint64_t e) {
  std::uint64_t r = 1;
  while (e > 0) {
    if (e & 1) r = MulMod(r, a);
    a = MulMod(a, a);
    e >>= 1;
  }
  return r;
}
std::uint64_t InvMod(std::uint64_t a) { return PowMod(a, kPrime - 2); }

// Determinant of a square matrix modulo kPrime (row-major, destroyed).
std::uint64_t DeterminantMod(std::vector<std::uint64_t>& a, int n) {
  std::uint64_t det = 1;
  for (int col = 0; col < n; ++col) {
    int pivot = col;
    while (pivot < n && a[pivot * n + col] == 0) ++pivot;
    if (pivot == n) return 0;
    if (pivot != col) {
      for (int k = 0; k < n; ++k) std::swap(a[pivot * n + k], a[col * n + k]);
      det = SubMod(0, det);
    }
    const std::uint64_t p = a[col * n + col];
    det = MulMod(det, p);
    const std::uint64_t inv = InvMod(p);
    for (int row = col + 1; row < n; ++row) {
      const std::uint64_t f = MulMod(a[row * n + col], inv);
      if (f == 0) continue;
      for (int k = col; k < n; ++k) {
        a[row * n + k] = SubMod(a[row * n + k], MulMod(f, a[col * n + k]));
      }
    }
  }
  return det;
}

// Coefficients (in x^0..x^(n-1)) of the polynomial through (xs[i], ys[i]) modulo kPrime.
std::vector<std::uint64_t> InterpolateMod(const std::vector<std::uint64_t>& xs,
                                          const std::vector<std::uint64_t>& ys) {
  const int n = static_cast<int>(xs.size());
  // Newton divided differences.
  std::vector<std::uint64_t> dd = ys;
  for (int level = 1; level < n; ++level) {
    for (int i = n - 1; i >= level; --i) {
      dd[i] = MulMod(SubMod(dd[i], dd[i - 1]), InvMod(SubMod(xs[i], xs[i - level])));
    }
  }
  // Horner expansion of the Newton form.
  std::vector<std::uint64_t> coeff(n, 0);
  for (int i = n - 1; i >= 0; --i) {
    // coeff = coeff * (x - xs[i]) + dd[i]
    std::vector<std::uint64_t> next(n, 0);
    for (int k = 0; k < n; ++k) {
      if (coeff[k] == 0) continue;
      if (k + 1 < n) next[k + 1] = AddMod(next[k + 1], coeff[k]);
      next[k] = SubMod(next[k], MulMod(coeff[k], xs[i]));
    }
    next[0] = AddMod(next[0], dd[i]);
    coeff = std::move(next);
  }
  return coeff;
}

// Exact determinant of a small integer matrix (Bareiss fraction-free elimination).
std::int64_t DeterminantExact(std::vector<Int128> a, int n) {
  if (n == 0) return 1;
  Int128 prev = 1;
  int sign = 1;
  for (int k = 0; k < n - 1; ++k) {
    if (a[k * n + k] == 0) {
      int swap_row = k + 1;
      while (swap_row < n && a[swap_row * n + k] == 0) ++swap_row;
      if (swap_row == n) return 0;
      for (int j = 0; j < n; ++j) std::swap(a[k * n + j], a[swap_row * n + j]);
      sign = -sign;
    }
    for (int i = k + 1; i < n; ++i) {
      for (int j = k + 1; j < n; ++j) {
        a[i * n + j] = (a[i * n + j] * a[k * n + k] - a[i * n + k] * a[k * n + j]) / prev;
      }
    }
    prev = a[k * n + k];
  }
  return static_cast<std::int64_t>(sign * a[(n - 1) * n + (n - 1)]);
}

// Union-find with undo (no path compression) for the bracket state sum.
class RollbackUnionFind {
 public:
  explicit RollbackUnionFind(int n) : parent_(n), rank_(n, 0), components_(n) {
    for (int i = 0; i < n; ++i) parent_[i] = i;
  }
  int Find(int x) const {
    while (parent_[x] != x) x = parent_[x];
    return x;
  }
  void Union(int a, int b) {
    a = Find(a);
    b = Find(b);
    if (a == b) {
      history_.push_back({-1, false});
      return;
    }
    if (rank_[a] < rank_[b]) std::swap(a, b);
    const bool rank_up = rank_[a] == rank_[b];
    parent_[b] = a;
    if (rank_up) ++rank_[a];
    --components_;
    history_.push_back({b, rank_up});
  }
  void Undo() {
    const auto [b, rank_up] = history_.back();
    history_.pop_back();
    if (b < 0) return;
    const int a = parent_[b];
    parent_[b] = b;
    if (rank_up) --rank_[a];
    ++components_;
  }
  int components() const { return components_; }

 private:
  std::vector<int> parent_;
  std::vector<int> rank_;
  int components_;
  std::vector<std::pair<int, bool>> history_;
};

void BracketStates(const PlanarDiagram& pd, int c, int num_a, RollbackUnionFind& uf,
                   std::vector<std::vector<std::int64_t>>& counts) {
  if (c == pd.num_crossings()) {
    ++counts[num_a][uf.components()];
    return;
  }
  const auto& s = pd.slots[c];
  // A-smoothing joins the corners swept by turning the over-strand counter-clockwise
  // (corners 1 and 3), i.e. it connects slot 0 with 1 and slot 2 with 3.
  uf.Union(s[0], s[1]);
  uf.Union(s[2], s[3]);
  BracketStates(pd, c + 1, num_a + 1, uf, counts);
  uf.Undo();
  uf.Undo();
  uf.Union(s[0], s[3]);
  uf.Union(s[1], s[2]);
  BracketStates(pd, c + 1, num_a, uf, counts);
  uf.Undo();
  uf.Undo();
}

}  // namespace

LaurentPolynomial AlexanderPolynomial(const PlanarDiagram& pd) {
  const int n = pd.num_crossings();
  if (n <= 1) return LaurentPolynomial{0, {1}};
  const int m = pd.num_edges();
  const auto& passages = pd.code.passages;
  // Arcs run from one under-passage to the next.
  int first_under = 0;
  while (passages[first_under].over) ++first_under;
  std::vector<int> edge_arc(m, -1);
  int arc = 0;
  for (int step = 0; step < m; ++step) {
    const int e = (first_under + step) % m;
    edge_arc[e] = arc;
    if (!passages[(e + 1) % m].over) ++arc;
  }
  MICRODEX_CHECK(arc == n);
  // Row c: constant and linear coefficients (M = M0 + t M1).
  std::vector<std::int64_t> m0(n * n, 0);
  std::vector<std::int64_t> m1(n * n, 0);
  for (int k = 0; k < m; ++k) {
    if (passages[k].over) continue;
    const int c = passages[k].crossing;
    const int in_arc = edge_arc[(k + m - 1) % m] % n;
    const int out_arc = edge_arc[k] % n;
    // The over-arc at c is the arc of the edge entering its over-passage.
    const int over_edge = pd.slots[c][pd.code.sign[c] > 0 ? 3 : 1];
    const int over_arc = edge_arc[over_edge] % n;
    // Fox derivatives of the Wirtinger relation x_out = x_over x_in x_over^-1 (positive)
    // or x_over^-1 x_in x_over (negative, row times t).
    if (pd.code.sign[c] > 0) {
      m0[c * n + over_arc] += 1;  // 1 - t
      m1[c * n + over_arc] -= 1;
      m1[c * n + in_arc] += 1;   // t
      m0[c * n + out_arc] -= 1;  // -1
    } else {
      m0[c * n + over_arc] -= 1;  // t - 1
      m1[c * n + over_arc] += 1;
      m0[c * n + in_arc] += 1;   // 1
      m1[c * n + out_arc] -= 1;  // -t
    }
  }
  // Delete the last row and column; the minor has degree <= n - 1.
  const int size = n - 1;
  std::vector<std::uint64_t> xs(n);
  std::vector<std::uint64_t> ys(n);
  std::vector<std::uint64_t> a(size * size);
  for (int i = 0; i < n; ++i) {
    const std::uint64_t t = static_cast<std::uint64_t>(i) + 2;
    xs[i] = t;
    for (int r = 0; r < size; ++r) {
      for (int col = 0; col < size; ++col) {
        a[r * size + col] =
            AddMod(FromSigned(m0[r * n + col]), MulMod(t, FromSigned(m1[r * n + col])));
      }
    }
    ys[i] = DeterminantMod(a, size);
  }
  const std::vector<std::uint64_t> coeff_mod = InterpolateMod(xs, ys);
  std::vector<std::int64_t> coeff(coeff_mod.size());
  for (std::size_t i = 0; i < coeff.size(); ++i) coeff[i] = ToSigned(coeff_mod[i]);
  LaurentPolynomial p = Trimmed(LaurentPolynomial{0, std::move(coeff)});
  const auto& c = p.coefficients;
  LaurentPolynomial invalid{0, {}};
  if (c.empty() || c.size() % 2 == 0) return invalid;
  for (std::size_t i = 0; i < c.size(); ++i) {
    if (c[i] != c[c.size() - 1 - i]) return invalid;
  }
  p.min_power = -static_cast<int>(c.size() - 1) / 2;
  if (p.coefficients.back() < 0) {
    for (auto& v : p.coefficients) v = -v;
  }
  if (std::llabs(EvaluateAtPlusMinusOne(p, 1)) != 1) return invalid;
  return p;
}

GoeritzResult GoeritzSignature(const PlanarDiagram& pd, int shade_color) {
  const int n = pd.num_crossings();
  if (n == 0) return GoeritzResult{0, 1};
  // Checkerboard colouring: the faces on the two sides of an edge differ.
  std::vector<std::vector<int>> neighbours(pd.num_faces);
  for (int c = 0; c < n; ++c) {
    for (int k = 0; k < 4; ++k) {
      const int f1 = pd.face_of_corner[4 * c + k];
      const int f2 = pd.face_of_corner[4 * c + (k + 1) % 4];
      neighbours[f1].push_back(f2);
      neighbours[f2].push_back(f1);
    }
  }
  std::vector<int> color(pd.num_faces, -1);
  std::queue<int> queue;
  color[0] = 0;
  queue.push(0);
  while (!queue.empty()) {
    const int f = queue.front();
    queue.pop();
    for (int g : neighbours[f]) {
      if (color[g] < 0) {
        color[g] = 1 - color[f];
        queue.push(g);
      }
      MICRODEX_CHECK(color[g] != color[f]);
    }
  }
  std::vector<int> white_index(pd.num_faces, -1);
  int num_white = 0;
  for (int f = 0; f < pd.num_faces; ++f) {
    if (color[f] != shade_color) white_index[f] = num_white++;
  }
  // Goeritz matrix over the white faces; the row and column of white face 0 are dropped.
  const int size = num_white - 1;
  std::vector<std::int64_t> g(static_cast<std::size_t>(num_white) * num_white, 0);
  int mu = 0;
  for (int c = 0; c < n; ++c) {
    const bool odd_white = color[pd.face_of_corner[4 * c + 1]] != shade_color;
    // eta = -1 when turning the over-strand (slots 1, 3) counter-clockwise sweeps the white
    // corners 1 and 3, +1 when it sweeps the shaded ones.
    const int eta = odd_white ? -1 : 1;
    const int w1 = white_index[pd.face_of_corner[4 * c + (odd_white ? 1 : 0)]];
    const int w2 = white_index[pd.face_of_corner[4 * c + (odd_white ? 3 : 2)]];
    if (w1 != w2) {
      g[w1 * num_white + w2] -= eta;
      g[w2 * num_white + w1] -= eta;
      g[w1 * num_white + w1] += eta;
      g[w2 * num_white + w2] += eta;
    }
    // Shaded corners are coherent (one edge in, one out) at corners 0, 2 of a positive
    // crossing and 1, 3 of a negative one; incoherent shaded corners make type II.
    const bool shaded_odd = !odd_white;
    const bool coherent = (pd.code.sign[c] > 0) != shaded_odd;
    if (!coherent) mu += eta;
  }
  GoeritzResult result;
  if (size <= 0) {
    result.signature = -mu;
    result.determinant = 1;
    return result;
  }
  Eigen::MatrixXd gd(size, size);
  std::vector<Int128> gi(static_cast<std::size_t>(size) * size);
  for (int i = 0; i < size; ++i) {
    for (int j = 0; j < size; ++j) {
      const std::int64_t v = g[(i + 1) * num_white + (j + 1)];
      gd(i, j) = static_cast<double>(v);
      gi[i * size + j] = v;
    }
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(gd, Eigen::EigenvaluesOnly);
  int sign_g = 0;
  for (int i = 0; i < size; ++i) {
    sign_g += eig.eigenvalues()(i) > 0 ? 1 : -1;
  }
  result.signature = sign_g - mu;
  result.determinant = std::llabs(DeterminantExact(std::move(gi), size));
  return result;
}

LaurentPolynomial JonesPolynomial(const PlanarDiagram& pd) {
  const int n = pd.num_crossings();
  if (n == 0) return LaurentPolynomial{0, {1}};
  // counts[a][loops]: states with `a` A-smoothings and `loops` circles.
  std::vector<std::vector<std::int64_t>> counts(n + 1,
                                                std::vector<std::int64_t>(pd.num_edges() + 1, 0));
  RollbackUnionFind uf(pd.num_edges());
  BracketStates(pd, 0, 0, uf, counts);
  // <D> = sum A^(a - b) d^(loops - 1), d = -A^2 - A^-2 (polynomials in A).
  const LaurentPolynomial d{-2, {-1, 0, 0, 0, -1}};
  LaurentPolynomial bracket{0, {}};
  std::vector<LaurentPolynomial> d_powers{LaurentPolynomial{0, {1}}};
  for (int a = 0; a <= n; ++a) {
    for (int loops = 1; loops <= pd.num_edges(); ++loops) {
      const std::int64_t count = counts[a][loops];
      if (count == 0) continue;
      while (static_cast<int>(d_powers.size()) < loops) {
        d_powers.push_back(Multiply(d_powers.back(), d));
      }
      LaurentPolynomial term = d_powers[loops - 1];
      term.min_power += a - (n - a);
      for (auto& v : term.coefficients) v *= count;
      bracket = Add(bracket, term);
    }
  }
  // f = (-A^3)^-w <D>.
  const int w = Writhe(pd.code);
  bracket.min_power -= 3 * w;
  if (w % 2 != 0) {
    for (auto& v : bracket.coefficients) v = -v;
  }
  // A = t^(-1/4): A^k -> t^(-k/4); a knot's exponents are multiples of 4.
  const auto& c = bracket.coefficients;
  const int max_a = bracket.min_power + static_cast<int>(c.size()) - 1;
  std::vector<std::int64_t> t_coeff;
  for (int k = max_a; k >= bracket.min_power; --k) {
    const std::int64_t v = c[k - bracket.min_power];
    if (k % 4 != 0) {
      MICRODEX_CHECK(v == 0);
      continue;
    }
    t_coeff.push_back(v);
  }
  MICRODEX_CHECK(max_a % 4 == 0);
  return Trimmed(LaurentPolynomial{-max_a / 4, std::move(t_coeff)});
}

}  // namespace microdex::knot
