// QpSolver: the problem format, its text form and the solver factory (qp_solver.h).
#include "ehc_control/qp_solver.h"

#include "ehc_control/dual_active_set_qp.h"

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

void writeMatrix(std::ostream& os, const char* name, const Eigen::MatrixXd& m) {
  os << name << ' ' << m.rows() << ' ' << m.cols() << '\n';
  for (Eigen::Index i = 0; i < m.rows(); ++i) {
    for (Eigen::Index j = 0; j < m.cols(); ++j) os << (j ? " " : "") << m(i, j);
    os << '\n';
  }
}

void readMatrix(std::istream& is, const char* name, Eigen::MatrixXd& m) {
  std::string tag;
  Eigen::Index rows = 0, cols = 0;
  if (!(is >> tag >> rows >> cols) || tag != name || rows < 0 || cols < 0)
    throw std::runtime_error(std::string("[QpProblem] expected matrix '") + name + "', got '" + tag + "'");
  m.resize(rows, cols);
  for (Eigen::Index i = 0; i < rows; ++i)
    for (Eigen::Index j = 0; j < cols; ++j)
      if (!(is >> m(i, j))) throw std::runtime_error(std::string("[QpProblem] short matrix '") + name + "'");
}

void readVector(std::istream& is, const char* name, Eigen::VectorXd& v) {
  Eigen::MatrixXd m;
  readMatrix(is, name, m);
  if (m.cols() != 1) throw std::runtime_error(std::string("[QpProblem] '") + name + "' must have 1 column");
  v = m.col(0);
}

}  // namespace

void QpProblem::write(std::ostream& os) const {
  const auto flags = os.flags();
  const auto precision = os.precision();
  os << std::setprecision(17);
  writeMatrix(os, "G", G);
  writeMatrix(os, "g", g);
  writeMatrix(os, "A", A);
  writeMatrix(os, "b", b);
  writeMatrix(os, "C", C);
  writeMatrix(os, "d", d);
  os.flags(flags);
  os.precision(precision);
}

QpProblem QpProblem::read(std::istream& is) {
  QpProblem p;
  readMatrix(is, "G", p.G);
  readVector(is, "g", p.g);
  readMatrix(is, "A", p.A);
  readVector(is, "b", p.b);
  readMatrix(is, "C", p.C);
  readVector(is, "d", p.d);
  return p;
}

std::vector<std::string> qpSolverNames() { return {"dual_active_set"}; }

std::unique_ptr<QpSolver> makeQpSolver(const std::string& name) {
  if (name == "dual_active_set") return std::make_unique<DualActiveSetQp>();
  std::string known;
  for (const std::string& n : qpSolverNames()) known += (known.empty() ? "" : ", ") + n;
  throw std::invalid_argument("[QpSolverFactory] unknown QP solver '" + name + "' (known: " + known + ")");
}

}  // namespace ehc_control
