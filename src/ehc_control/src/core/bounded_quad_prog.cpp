// BoundedQuadProg: vpQuadProg::solveQP / solveQPi of ViSP 3.5.0
// (modules/core/src/tools/optimization/vpQuadProg.cpp, GPL v2, Inria) with an iteration limit on
// the active-set loop; otherwise the same operations in the same order (so the same results),
// without the console messages (the caller reports the reason).
#include "ehc_control/bounded_quad_prog.h"

#include <visp3/core/vpLinProg.h>

#include <algorithm>
#include <iomanip>
#include <istream>
#include <ostream>
#include <stdexcept>

namespace ehc_control {

std::string toString(QpSolveResult r) {
  switch (r) {
    case QpSolveResult::Solved: return "solved";
    case QpSolveResult::Infeasible: return "infeasible";
    case QpSolveResult::IterationLimit: return "iteration limit";
  }
  return "unknown";
}

namespace {
void writeMatrix(std::ostream& os, const char* name, const vpArray2D<double>& m) {
  os << name << ' ' << m.getRows() << ' ' << m.getCols() << '\n';
  for (unsigned int i = 0; i < m.getRows(); ++i) {
    for (unsigned int j = 0; j < m.getCols(); ++j) os << (j ? " " : "") << m[i][j];
    os << '\n';
  }
}
void readMatrix(std::istream& is, const char* name, vpArray2D<double>& m) {
  std::string tag;
  unsigned int rows = 0, cols = 0;
  if (!(is >> tag >> rows >> cols) || tag != name)
    throw std::runtime_error(std::string("[QpProblem] expected matrix '") + name + "', got '" + tag + "'");
  m.resize(rows, cols, true);
  for (unsigned int i = 0; i < rows; ++i)
    for (unsigned int j = 0; j < cols; ++j)
      if (!(is >> m[i][j])) throw std::runtime_error(std::string("[QpProblem] short matrix '") + name + "'");
}
void writeSet(std::ostream& os, const char* name, const std::vector<unsigned int>& v) {
  os << name << ' ' << v.size();
  for (unsigned int i : v) os << ' ' << i;
  os << '\n';
}
void readSet(std::istream& is, const char* name, std::vector<unsigned int>& v) {
  std::string tag;
  std::size_t n = 0;
  if (!(is >> tag >> n) || tag != name)
    throw std::runtime_error(std::string("[QpProblem] expected set '") + name + "', got '" + tag + "'");
  v.resize(n);
  for (auto& i : v)
    if (!(is >> i)) throw std::runtime_error(std::string("[QpProblem] short set '") + name + "'");
}
}  // namespace

void QpProblem::write(std::ostream& os) const {
  const auto flags = os.flags();
  const auto precision = os.precision();
  os << std::setprecision(17);
  os << "tol " << tol << '\n';
  writeMatrix(os, "Q", Q);
  writeMatrix(os, "r", r);
  writeMatrix(os, "A", A);
  writeMatrix(os, "b", b);
  writeMatrix(os, "C", C);
  writeMatrix(os, "d", d);
  writeSet(os, "active", active);
  writeSet(os, "inactive", inactive);
  os.flags(flags);
  os.precision(precision);
}

QpProblem QpProblem::read(std::istream& is) {
  QpProblem p;
  std::string tag;
  if (!(is >> tag >> p.tol) || tag != "tol") throw std::runtime_error("[QpProblem] expected 'tol'");
  readMatrix(is, "Q", p.Q);
  readMatrix(is, "r", p.r);
  readMatrix(is, "A", p.A);
  readMatrix(is, "b", p.b);
  readMatrix(is, "C", p.C);
  readMatrix(is, "d", p.d);
  readSet(is, "active", p.active);
  readSet(is, "inactive", p.inactive);
  return p;
}

void BoundedQuadProg::setWarmStart(const std::vector<unsigned int>& active_set,
                                   const std::vector<unsigned int>& inactive_set) {
  active = active_set;
  inactive = inactive_set;
}

QpSolveResult BoundedQuadProg::solveQP(const vpMatrix& Q, const vpColVector& r, const vpMatrix& A,
                                       const vpColVector& b, const vpMatrix& C, const vpColVector& d, vpColVector& x,
                                       double tol, int max_iterations) {
  start_active_ = active;  // kept for lastIterationLimitProblem() (no allocation once sized)
  start_inactive_ = inactive;
  A_work_ = A;  // vpQuadProg::solveQP takes A, b by value and reduces them in place
  b_work_ = b;
  const QpSolveResult res = solve(Q, r, A_work_, b_work_, C, d, x, tol, max_iterations);
  if (res == QpSolveResult::IterationLimit)
    limit_problem_ = QpProblem{Q, A, C, r, b, d, start_active_, start_inactive_, tol};
  return res;
}

QpSolveResult BoundedQuadProg::solve(const vpMatrix& Q, const vpColVector& r, vpMatrix& A, vpColVector& b,
                                     const vpMatrix& C, const vpColVector& d, vpColVector& x, double tol,
                                     int max_iterations) {
  iterations_ = 0;
  if (A.getRows() == 0) return solveQPi(Q, r, C, d, x, tol, max_iterations);
  checkDimensions(Q, r, &A, &b, &C, &d, "solveQP");
  if (!vpLinProg::colReduction(A, b, false, tol)) return QpSolveResult::Infeasible;
  if (A.getCols()) {
    const QpSolveResult res = solveQPi(Q * A, r - Q * b, C * A, d - C * b, x, tol, max_iterations);
    if (res == QpSolveResult::Solved) {
      x = b + A * x;
      return res;
    }
    if (res == QpSolveResult::IterationLimit) return res;
  }
  if (vpLinProg::allLesser(C, b, d, tol)) {  // Ax = b has only 1 solution
    x = b;
    return QpSolveResult::Solved;
  }
  return QpSolveResult::Infeasible;
}

QpSolveResult BoundedQuadProg::solveQPi(const vpMatrix& Q, const vpColVector& r, const vpMatrix& C,
                                        const vpColVector& d, vpColVector& x, double tol, int max_iterations) {
  const unsigned int n = checkDimensions(Q, r, nullptr, nullptr, &C, &d, "solveQPi");
  const unsigned int p = C.getRows();

  // trivial solution: r = 0 and d > 0 -> x = 0
  if (vpLinProg::allZero(r, tol) && (d.getRows() == 0 || vpLinProg::allGreater(d, -tol))) {
    x.resize(n);
    return QpSolveResult::Solved;
  }

  vpMatrix A;
  vpColVector b;
  for (auto v : active)
    if (v >= p) {  // constraints removed since the last call
      active.clear();
      break;
    }

  // warm start from the previous active set
  A.resize(static_cast<unsigned int>(active.size()), n);
  b.resize(static_cast<unsigned int>(active.size()));
  for (unsigned int i = 0; i < active.size(); ++i) {
    for (unsigned int j = 0; j < n; ++j) A[i][j] = C[active[i]][j];
    b[i] = d[active[i]];
  }
  if (!solveByProjection(Q, r, A, b, x, tol)) x.resize(n);

  // or a feasible point from the simplex if the warm start is not feasible:
  //   min r  s.t. C (x + z1 - z2) + y - r = d,  z1, z2, y, r >= 0
  if (!vpLinProg::allLesser(C, x, d, tol)) {
    vpColVector e = d - C * x;
    unsigned int k = 0;
    for (unsigned int i = 0; i < p; ++i)
      if (e[i] < -tol) k++;
    vpColVector c(2 * n + p + k);
    for (unsigned int i = 0; i < k; ++i) c[2 * n + p + i] = 1;
    vpColVector xc(2 * n + p + k);
    vpMatrix A_lp(p, 2 * n + p + k);
    unsigned int l = 0;
    for (unsigned int i = 0; i < p; ++i) {
      for (unsigned int j = 0; j < n; ++j) {
        A_lp[i][j] = C[i][j];
        A_lp[i][n + j] = -C[i][j];
      }
      A_lp[i][2 * n + i] = 1;
      if (e[i] < -tol) {
        A_lp[i][2 * n + p + l] = -1;
        xc[2 * n + p + l] = -e[i];
        l++;
      } else
        xc[2 * n + i] = e[i];
    }
    vpLinProg::simplex(c, A_lp, e, xc);
    if (!vpLinProg::allLesser(xc.extract(2 * n + p, k), tol)) return QpSolveResult::Infeasible;
    x += xc.extract(0, n) - xc.extract(n, n);
    active.clear();
    active.reserve(p);
    inactive.clear();
    for (unsigned int i = 0; i < p; ++i) {
      if (C.getRow(i) * x - d[i] < -tol)
        inactive.push_back(i);
      else
        active.push_back(i);
    }
  } else if (active.size() + inactive.size() != p) {  // warm start feasible: sync the inactive set
    inactive.clear();
    for (unsigned int i = 0; i < p; ++i)
      if (std::find(active.begin(), active.end(), i) == active.end()) inactive.push_back(i);
  }

  vpMatrix Ap;
  bool update_Ap = true;
  unsigned int last_active = C.getRows();
  vpColVector u, g = r - Q * x, mu;

  // vpQuadProg: while (true)
  for (iterations_ = 0; iterations_ < max_iterations; ++iterations_) {
    A.resize(static_cast<unsigned int>(active.size()), n);
    b.resize(static_cast<unsigned int>(active.size()));
    for (unsigned int i = 0; i < active.size(); ++i)
      for (unsigned int j = 0; j < n; ++j) A[i][j] = C[active[i]][j];
    if (update_Ap && active.size()) Ap = A.pseudoInverse();  // Lagrange multipliers if needed

    if (!solveByProjection(Q, g, A, b, u, tol)) return QpSolveResult::Infeasible;  // too many active

    if (vpLinProg::allZero(u, tol)) {  // optimal, or useless activated constraints
      unsigned int ineqInd = static_cast<unsigned int>(active.size());
      if (active.size()) {
        mu = -Ap.transpose() * Q.transpose() * (Q * u - g);
        // most negative multiplier, except the last activated (degeneracy)
        double ineqMax = -tol;
        for (unsigned int i = 0; i < mu.getRows(); ++i)
          if (mu[i] < ineqMax && active[i] != last_active) {
            ineqInd = i;
            ineqMax = mu[i];
          }
      }
      if (ineqInd == active.size()) {  // KKT
        ++iterations_;
        return QpSolveResult::Solved;
      }
      inactive.push_back(active[ineqInd]);  // useless inequality, deactivate
      if (active.size() == 1)
        active.clear();
      else
        active.erase(active.begin() + ineqInd);
      update_Ap = true;
    } else {  // u != 0: step to the next blocking constraint
      unsigned int ineqInd = 0;
      double alpha = 1;
      for (unsigned int i = 0; i < inactive.size(); ++i) {
        const double Cu = C.getRow(inactive[i]) * u;
        if (Cu > tol) {
          const double a = (d[inactive[i]] - C.getRow(inactive[i]) * x) / Cu;
          if (a < alpha) {
            alpha = a;
            ineqInd = i;
          }
        }
      }
      if (alpha < 1) {
        last_active = inactive[ineqInd];
        if (active.size()) {
          auto it = active.begin();
          while (it != active.end() && *it < inactive[ineqInd]) it++;
          active.insert(it, inactive[ineqInd]);
        } else
          active.push_back(inactive[ineqInd]);
        inactive.erase(inactive.begin() + ineqInd);
        update_Ap = true;
      } else
        update_Ap = false;
      x += alpha * u;
      g -= alpha * Q * u;
    }
  }
  return QpSolveResult::IterationLimit;
}

}  // namespace ehc_control
