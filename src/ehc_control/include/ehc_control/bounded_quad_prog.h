#pragma once
// BoundedQuadProg: ViSP's vpQuadProg::solveQP (least-squares form, equality + inequality
// constraints, active set warm-started between calls) with an iteration limit.
//
// vpQuadProg::solveQPi (ViSP 3.5.0) iterates its primal active-set loop `while (true)`: on a
// degenerate vertex (several inequality rows active with a zero step, e.g. slack and velocity
// bounds meeting obstacle rows) it can add and drop the same constraints forever, and the
// control cycle never returns. This class runs the same algorithm -- the same steps, the same
// tolerances and the same warm start, so a solve that terminates gives vpQuadProg's result bit
// for bit -- but counts the active-set iterations and gives up after `max_iterations`.
// ROS-free.

#include <visp3/core/vpQuadProg.h>

#include <iosfwd>
#include <string>
#include <vector>

namespace ehc_control {

enum class QpSolveResult {
  Solved,          ///< x is the solution
  Infeasible,      ///< equality or inequality constraints infeasible (x unspecified)
  IterationLimit,  ///< no optimum within max_iterations active-set steps (x unspecified)
};
std::string toString(QpSolveResult r);

/// One solveQP call: the problem and the warm start (active and inactive sets) it began with.
/// Plain text (write/read round-trip exactly, %.17g), for capturing a failing solve and
/// replaying it in a test.
struct QpProblem {
  vpMatrix Q, A, C;
  vpColVector r, b, d;
  std::vector<unsigned int> active, inactive;
  double tol = 1e-6;
  void write(std::ostream& os) const;
  static QpProblem read(std::istream& is);  ///< throws std::runtime_error "[QpProblem] ..."
};

class BoundedQuadProg : public vpQuadProg {
 public:
  /// min |Q x - r|^2  s.t.  A x = b,  C x <= d  (vpQuadProg::solveQP); A may have 0 rows.
  /// Throws what vpQuadProg's linear algebra throws (vpException). Never loops unboundedly:
  /// the active-set loop runs at most max_iterations times; the phase-1 search for a feasible
  /// point (when the warm start is infeasible) is vpLinProg::simplex (see the .cpp).
  QpSolveResult solveQP(const vpMatrix& Q, const vpColVector& r, const vpMatrix& A, const vpColVector& b,
                        const vpMatrix& C, const vpColVector& d, vpColVector& x, double tol, int max_iterations);
  /// Active-set iterations of the last solveQP call.
  int iterations() const { return iterations_; }
  /// The warm start of the next call (tests: replay a captured problem).
  void setWarmStart(const std::vector<unsigned int>& active_set, const std::vector<unsigned int>& inactive_set);
  const std::vector<unsigned int>& activeSet() const { return active; }
  const std::vector<unsigned int>& inactiveSet() const { return inactive; }
  /// The last call that ended in IterationLimit, with the warm start it began with (empty
  /// matrices if none): what the caller may write out for diagnosis.
  const QpProblem& lastIterationLimitProblem() const { return limit_problem_; }

 private:
  QpSolveResult solve(const vpMatrix& Q, const vpColVector& r, vpMatrix& A, vpColVector& b, const vpMatrix& C,
                      const vpColVector& d, vpColVector& x, double tol, int max_iterations);
  QpSolveResult solveQPi(const vpMatrix& Q, const vpColVector& r, const vpMatrix& C, const vpColVector& d,
                         vpColVector& x, double tol, int max_iterations);
  int iterations_ = 0;
  std::vector<unsigned int> start_active_, start_inactive_;  ///< warm start of this call
  vpMatrix A_work_;
  vpColVector b_work_;
  QpProblem limit_problem_;
};

}  // namespace ehc_control
