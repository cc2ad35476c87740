// DualActiveSetQp: Goldfarb-Idnani dual active-set method (dual_active_set_qp.h).
//
// Notation (the paper's, with constraints written as n_i^T x >= b_i): an inequality row
// C_i x <= d_i is n_i = -C_i^T, b_i = -d_i; an equality row A_i x = b_i enters with the sign
// that makes it violated at the current x. s_p(x) = n_p^T x - b_p < 0 for a violated p.
// With the active normals N (n x k), J = L^-T Q and J^T N = [R; 0]:
//   d = J^T n_p,  z = J2 d2 (primal step direction: H n_p, H the reduced inverse Hessian),
//   r = R^-1 d1 (dual step direction: N* n_p).
// Step length t = min(t1, t2): t2 = -s_p / z^T n_p makes p active (full step); t1 =
// min_j u_j / r_j over active inequalities with r_j > 0 drops the constraint j whose
// multiplier reaches 0 first (partial step). z = 0 (n_p depends on the active normals) allows
// only partial steps; no step at all means the constraints are infeasible.
#include "ehc_control/dual_active_set_qp.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>

namespace ehc_control {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
/// n_p counts as linearly dependent on the active normals when the part of d = J^T n_p outside
/// the active span is below this fraction of |d|.
constexpr double kDependent = 1e-10;

/// Givens rotation (c, s) with [c s; -s c] [a; b] = [h; 0]; returns h.
double givens(double a, double b, double* c, double* s) {
  const double h = std::hypot(a, b);
  if (h == 0.0) {
    *c = 1.0;
    *s = 0.0;
  } else {
    *c = a / h;
    *s = b / h;
  }
  return h;
}

/// Columns i, j of M  <-  (c M_i + s M_j, -s M_i + c M_j).
void rotateColumns(Eigen::MatrixXd& M, Eigen::Index i, Eigen::Index j, double c, double s) {
  for (Eigen::Index r = 0; r < M.rows(); ++r) {
    const double a = M(r, i), b = M(r, j);
    M(r, i) = c * a + s * b;
    M(r, j) = -s * a + c * b;
  }
}

}  // namespace

std::vector<int> DualActiveSetQp::activeInequalities() const {
  std::vector<int> rows;
  for (int j = 0; j < k_; ++j)
    if (active_[static_cast<std::size_t>(j)] >= n_eq_) rows.push_back(active_[static_cast<std::size_t>(j)] - n_eq_);
  std::sort(rows.begin(), rows.end());
  return rows;
}

Eigen::VectorXd DualActiveSetQp::inequalityMultipliers() const {
  Eigen::VectorXd lambda = Eigen::VectorXd::Zero(n_in_);
  for (int j = 0; j < k_; ++j)
    if (active_[static_cast<std::size_t>(j)] >= n_eq_) lambda[active_[static_cast<std::size_t>(j)] - n_eq_] = u_[j];
  return lambda;
}

void DualActiveSetQp::addToActiveSet(int p, double u) {
  // Rotate d = J^T n_p so that only its first k + 1 entries remain (columns k.. of J rotate
  // along): the active normals' columns of J^T N keep their zeros below row k.
  for (int j = n_ - 1; j > k_; --j) {
    if (d_[j] == 0.0) continue;
    double c, s;
    d_[j - 1] = givens(d_[j - 1], d_[j], &c, &s);
    d_[j] = 0.0;
    rotateColumns(J_, j - 1, j, c, s);
  }
  R_.col(k_).head(k_ + 1) = d_.head(k_ + 1);
  active_[static_cast<std::size_t>(k_)] = p;
  u_[k_] = u;
  if (p >= n_eq_) in_active_[static_cast<std::size_t>(p - n_eq_)] = 1;
  ++k_;
}

void DualActiveSetQp::dropFromActiveSet(int l) {
  const int p = active_[static_cast<std::size_t>(l)];
  if (p >= n_eq_) in_active_[static_cast<std::size_t>(p - n_eq_)] = 0;
  for (int j = l; j + 1 < k_; ++j) {
    R_.col(j).head(k_) = R_.col(j + 1).head(k_);
    active_[static_cast<std::size_t>(j)] = active_[static_cast<std::size_t>(j + 1)];
    u_[j] = u_[j + 1];
  }
  --k_;
  // R is now upper Hessenberg from column l: rotate rows (j, j + 1) to clear R(j + 1, j).
  for (int j = l; j < k_; ++j) {
    double c, s;
    R_(j, j) = givens(R_(j, j), R_(j + 1, j), &c, &s);
    R_(j + 1, j) = 0.0;
    for (int col = j + 1; col < k_; ++col) {
      const double a = R_(j, col), b = R_(j + 1, col);
      R_(j, col) = c * a + s * b;
      R_(j + 1, col) = -s * a + c * b;
    }
    rotateColumns(J_, j, j + 1, c, s);
  }
}

QpSolveResult DualActiveSetQp::solve(const Eigen::Ref<const Eigen::MatrixXd>& G,
                                     const Eigen::Ref<const Eigen::VectorXd>& g,
                                     const Eigen::Ref<const Eigen::MatrixXd>& A,
                                     const Eigen::Ref<const Eigen::VectorXd>& b,
                                     const Eigen::Ref<const Eigen::MatrixXd>& C,
                                     const Eigen::Ref<const Eigen::VectorXd>& d, Eigen::VectorXd* x,
                                     int max_iterations, double tolerance) {
  start(G, g, A, b, C, d, x, max_iterations);
  int next_equality = 0;
  for (;;) {
    int p = -1;
    double bp = 0.0;
    if (const auto done = pickConstraint(A, b, C, d, *x, tolerance, &next_equality, &p, &bp)) return *done;
    if (const auto done = makeActive(p, bp, x, max_iterations, tolerance)) return *done;
  }
}

void DualActiveSetQp::start(const Eigen::Ref<const Eigen::MatrixXd>& G, const Eigen::Ref<const Eigen::VectorXd>& g,
                            const Eigen::Ref<const Eigen::MatrixXd>& A, const Eigen::Ref<const Eigen::VectorXd>& b,
                            const Eigen::Ref<const Eigen::MatrixXd>& C, const Eigen::Ref<const Eigen::VectorXd>& d,
                            Eigen::VectorXd* x, int max_iterations) {
  const Eigen::Index n = G.rows();
  if (n < 1 || G.cols() != n || g.size() != n || A.cols() != n || b.size() != A.rows() || C.cols() != n ||
      d.size() != C.rows())
    throw std::invalid_argument("[DualActiveSetQp] inconsistent problem sizes");
  if (max_iterations < 1) throw std::invalid_argument("[DualActiveSetQp] max_iterations must be >= 1");
  n_ = static_cast<int>(n);
  n_eq_ = static_cast<int>(A.rows());
  n_in_ = static_cast<int>(C.rows());
  k_ = 0;
  iterations_ = 0;

  llt_.compute(G);
  if (llt_.info() != Eigen::Success || !llt_.matrixLLT().allFinite())
    throw std::invalid_argument("[DualActiveSetQp] G is not positive definite");
  J_.setIdentity(n, n);
  llt_.matrixU().solveInPlace(J_);  // J = L^-T
  R_.resize(n, n);
  np_.resize(n);
  d_.resize(n);
  z_.resize(n);
  r_.resize(n);
  u_.resize(n);
  active_.resize(static_cast<std::size_t>(n));
  in_active_.assign(static_cast<std::size_t>(n_in_), 0);
  row_norm_.resize(n_in_);
  for (int i = 0; i < n_in_; ++i) row_norm_[i] = C.row(i).norm();

  // Unconstrained minimum.
  *x = -g;
  llt_.solveInPlace(*x);
}

std::optional<QpSolveResult> DualActiveSetQp::pickConstraint(const Eigen::Ref<const Eigen::MatrixXd>& A,
                                                             const Eigen::Ref<const Eigen::VectorXd>& b,
                                                             const Eigen::Ref<const Eigen::MatrixXd>& C,
                                                             const Eigen::Ref<const Eigen::VectorXd>& d,
                                                             const Eigen::VectorXd& x, double tolerance,
                                                             int* next_equality, int* p_out, double* bp) {
  int p = -1;
  while (*next_equality < n_eq_ && p < 0) {
    const int i = (*next_equality)++;
    const double a_norm = A.row(i).norm();
    const double residual = A.row(i).dot(x) - b[i];
    if (a_norm == 0.0) {
      if (std::abs(residual) > tolerance) return QpSolveResult::Infeasible;
      continue;  // 0 = 0
    }
    // Violated with the sign that makes s_p < 0 (a satisfied equality is still added: it
    // must stay satisfied while inequalities enter).
    const double sign = residual > 0.0 ? -1.0 : 1.0;
    np_ = sign * A.row(i).transpose();
    *bp = sign * b[i];
    p = i;
  }
  if (p < 0) {
    double worst = tolerance;
    for (int i = 0; i < n_in_; ++i) {
      if (in_active_[static_cast<std::size_t>(i)] || row_norm_[i] == 0.0) {
        if (row_norm_[i] == 0.0 && d[i] < -tolerance) return QpSolveResult::Infeasible;  // 0 <= d_i
        continue;
      }
      const double violation = (C.row(i).dot(x) - d[i]) / row_norm_[i];
      if (violation > worst) {
        worst = violation;
        p = n_eq_ + i;
      }
    }
    if (p < 0) return QpSolveResult::Solved;
    np_ = -C.row(p - n_eq_).transpose();
    *bp = -d[p - n_eq_];
  }
  *p_out = p;
  return std::nullopt;
}

std::optional<QpSolveResult> DualActiveSetQp::makeActive(int p, double bp, Eigen::VectorXd* x, int max_iterations,
                                                         double tolerance) {
  const bool p_equality = p < n_eq_;
  const Eigen::Index n = n_;
  double u_p = 0.0;  // multiplier of p
  for (;;) {
    if (iterations_ >= max_iterations) return QpSolveResult::IterationLimit;
    const double s_p = np_.dot(*x) - bp;
    d_.noalias() = J_.transpose() * np_;
    const Eigen::Index free = n - k_;
    const double d_norm2 = d_.squaredNorm();
    const double d2_norm2 = d_.tail(free).squaredNorm();
    const bool dependent = free == 0 || d2_norm2 <= kDependent * kDependent * d_norm2;
    if (dependent) {
      z_.setZero();
    } else {
      z_.noalias() = J_.rightCols(free) * d_.tail(free);
    }
    r_.head(k_) = d_.head(k_);
    R_.topLeftCorner(k_, k_).triangularView<Eigen::Upper>().solveInPlace(r_.head(k_));

    double t1 = kInf;  // partial step: an active inequality's multiplier reaches 0
    int l = -1;
    for (int j = 0; j < k_; ++j)
      if (active_[static_cast<std::size_t>(j)] >= n_eq_ && r_[j] > 0.0 && u_[j] / r_[j] < t1) {
        t1 = u_[j] / r_[j];
        l = j;
      }
    const double t2 = dependent ? kInf : -s_p / d2_norm2;  // z^T n_p = |d2|^2
    const double t = std::min(t1, t2);
    if (t == kInf) {
      // p depends on the active normals and no multiplier limits the dual step: no point
      // meets p and the active constraints (a dependent equality already met is skipped).
      if (p_equality && std::abs(s_p) <= tolerance * np_.norm()) return std::nullopt;
      return QpSolveResult::Infeasible;
    }
    ++iterations_;
    if (!dependent) *x += t * z_;
    u_.head(k_) -= t * r_.head(k_);
    u_p += t;
    if (t2 <= t1) {
      addToActiveSet(p, u_p);
      return std::nullopt;
    }
    dropFromActiveSet(l);  // and step again towards p
  }
}

}  // namespace ehc_control
