#pragma once
// QpSolver: the interface between the controller and a QP back end (as tsid's SolverHQPBase
// separates its task formulation from eiquadprog, proxsuite, ...). The controller builds one
// dense, strictly convex QP per cycle,
//
//   min 1/2 x^T G x + g^T x   s.t.   A x = b,   C x <= d        (G symmetric positive definite)
//
// hands it to the solver as a QpProblemView (references to its own workspace, nothing copied)
// and reads back the status, the solution and the number of iterations. A back end is chosen by
// name (makeQpSolver; controller.yaml `controller.qp_solver`); the one shipped is
// "dual_active_set" (DualActiveSetQp, dual_active_set_qp.h). Another back end implements
// QpSolver and is added to makeQpSolver and qpSolverNames. ROS-free.

#include <Eigen/Core>

#include <iosfwd>
#include <memory>
#include <string>
#include <vector>

namespace ehc_control {

enum class QpSolveResult {
  Solved,          ///< x is the solution
  Infeasible,      ///< the constraints have no common point (x unspecified)
  IterationLimit,  ///< not solved within max_iterations steps (x unspecified)
};
std::string toString(QpSolveResult r);

/// One QP as plain text (write/read round-trip exactly, %.17g): for capturing a problem and
/// replaying it in a test.
struct QpProblem {
  Eigen::MatrixXd G, A, C;
  Eigen::VectorXd g, b, d;
  void write(std::ostream& os) const;
  static QpProblem read(std::istream& is);  ///< throws std::runtime_error "[QpProblem] ..."
};

/// The QP above by reference: blocks of the caller's matrices are used in place (an expression
/// that is not one is evaluated into the view). A or C may have 0 rows (n columns still). Not
/// copyable: pass it by reference and keep it no longer than the matrices it refers to.
struct QpProblemView {
  template <typename MG, typename Vg, typename MA, typename Vb, typename MC, typename Vd>
  QpProblemView(const MG& G_, const Vg& g_, const MA& A_, const Vb& b_, const MC& C_, const Vd& d_)
      : G(G_), g(g_), A(A_), b(b_), C(C_), d(d_) {}
  QpProblemView(const QpProblem& p)  // implicit: a stored problem is solved as it is
      : G(p.G), g(p.g), A(p.A), b(p.b), C(p.C), d(p.d) {}
  QpProblemView(const QpProblemView&) = delete;
  QpProblemView& operator=(const QpProblemView&) = delete;

  const Eigen::Ref<const Eigen::MatrixXd> G;
  const Eigen::Ref<const Eigen::VectorXd> g;
  const Eigen::Ref<const Eigen::MatrixXd> A;
  const Eigen::Ref<const Eigen::VectorXd> b;
  const Eigen::Ref<const Eigen::MatrixXd> C;
  const Eigen::Ref<const Eigen::VectorXd> d;
};

class QpSolver {
 public:
  virtual ~QpSolver() = default;

  /// The name makeQpSolver knows it by, e.g. "dual_active_set".
  virtual std::string name() const = 0;

  /// Solves `problem` in at most max_iterations (>= 1) of the back end's steps; `x` is resized to
  /// n and holds the solution when the result is Solved. Throws std::invalid_argument
  /// "[<Solver>] ..." for mismatched sizes, max_iterations < 1 or a G that is not positive
  /// definite (or not finite). Once warm (same sizes), a solve allocates nothing.
  virtual QpSolveResult solve(const QpProblemView& problem, Eigen::VectorXd* x, int max_iterations) = 0;

  /// Steps of the last solve (<= its max_iterations).
  virtual int iterations() const = 0;
};

/// The names makeQpSolver accepts.
std::vector<std::string> qpSolverNames();
/// A new solver of that name; throws std::invalid_argument "[QpSolverFactory] unknown QP solver
/// '<name>' (known: ...)".
std::unique_ptr<QpSolver> makeQpSolver(const std::string& name);

}  // namespace ehc_control
