#pragma once
// DualActiveSetQp: a dense, strictly convex quadratic program
//
//   min 1/2 x^T G x + g^T x   s.t.   A x = b,   C x <= d        (G symmetric positive definite)
//
// solved with the dual active-set method of D. Goldfarb and A. Idnani, "A numerically stable
// dual method for solving strictly convex quadratic programs", Mathematical Programming 27
// (1983) 1-33. It starts at the unconstrained minimum -G^-1 g, which is optimal for the empty
// active set, and keeps the iterate optimal for its active set while it adds violated
// constraints one at a time (the equalities first, then the most violated inequality, measured
// in the units of x): a step in the primal and dual space makes the added constraint active; a
// constraint whose multiplier would turn negative on the way leaves the active set (a partial
// step). No feasible starting point is needed. The active normals N are held as
// J = L^-T Q and R, with G = L L^T and Q R = L^-1 N; adding and dropping a constraint updates
// them with Givens rotations.
//
// Every full step increases the dual objective, so the method terminates on non-degenerate
// problems. On degenerate ones (zero-length partial steps) it could revisit active sets; the
// number of add/drop steps is therefore bounded and the solve then reports IterationLimit.
// Once the workspace has the problem's size, solve() allocates nothing. ROS-free.

#include "ehc_control/qp_solver.h"

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include <optional>
#include <string>
#include <vector>

namespace ehc_control {

/// QpSolver "dual_active_set".
class DualActiveSetQp : public QpSolver {
 public:
  /// Feasibility tolerance: a constraint is met when C_i x - d_i <= tolerance |C_i| (for an
  /// equality |A_i x - b_i| <= tolerance |A_i|), i.e. within `tolerance` in the units of x.
  static constexpr double kDefaultTolerance = 1e-9;

  /// Solves the QP above. A or C may have 0 rows (their column count must still be n). Throws
  /// std::invalid_argument "[DualActiveSetQp] ..." for mismatched sizes or a G that is not
  /// positive definite (or not finite). At most max_iterations (>= 1) constraint additions and
  /// removals. `x` is resized to n.
  QpSolveResult solve(const Eigen::Ref<const Eigen::MatrixXd>& G, const Eigen::Ref<const Eigen::VectorXd>& g,
                      const Eigen::Ref<const Eigen::MatrixXd>& A, const Eigen::Ref<const Eigen::VectorXd>& b,
                      const Eigen::Ref<const Eigen::MatrixXd>& C, const Eigen::Ref<const Eigen::VectorXd>& d,
                      Eigen::VectorXd* x, int max_iterations, double tolerance = kDefaultTolerance);
  /// QpSolver: the solve above with the default tolerance.
  QpSolveResult solve(const QpProblemView& p, Eigen::VectorXd* x, int max_iterations) override {
    return solve(p.G, p.g, p.A, p.b, p.C, p.d, x, max_iterations);
  }
  std::string name() const override { return "dual_active_set"; }

  /// Add and drop steps of the last solve.
  int iterations() const override { return iterations_; }
  /// Rows of C active at the last solution (ascending), valid after Solved.
  std::vector<int> activeInequalities() const;
  /// Lagrange multiplier of each row of C at the last solution (0 for inactive rows), valid
  /// after Solved: G x + g + A^T lambda_eq + C^T lambda = 0, lambda >= 0.
  Eigen::VectorXd inequalityMultipliers() const;

 private:
  /// Checks the sizes, factorises G, sizes the workspace (empty active set) and sets x to the
  /// unconstrained minimum -G^-1 g.
  void start(const Eigen::Ref<const Eigen::MatrixXd>& G, const Eigen::Ref<const Eigen::VectorXd>& g,
             const Eigen::Ref<const Eigen::MatrixXd>& A, const Eigen::Ref<const Eigen::VectorXd>& b,
             const Eigen::Ref<const Eigen::MatrixXd>& C, const Eigen::Ref<const Eigen::VectorXd>& d,
             Eigen::VectorXd* x, int max_iterations);
  /// Step 1: the constraint to add next, the equalities first (from *next_equality on), then
  /// the most violated inequality (index n_eq + i); sets np_, *p and *bp. Returns Solved when
  /// x violates nothing, Infeasible for a zero row that cannot be met, else nothing.
  std::optional<QpSolveResult> pickConstraint(const Eigen::Ref<const Eigen::MatrixXd>& A,
                                              const Eigen::Ref<const Eigen::VectorXd>& b,
                                              const Eigen::Ref<const Eigen::MatrixXd>& C,
                                              const Eigen::Ref<const Eigen::VectorXd>& d, const Eigen::VectorXd& x,
                                              double tolerance, int* next_equality, int* p, double* bp);
  /// Step 2: primal and dual steps (dropping the active inequalities whose multiplier reaches
  /// 0) until constraint p (normal np_, right-hand side bp) is active, or skipped when it is an
  /// equality already met that depends on the active ones. Returns nothing then, else
  /// Infeasible or IterationLimit.
  std::optional<QpSolveResult> makeActive(int p, double bp, Eigen::VectorXd* x, int max_iterations, double tolerance);
  /// Adds constraint `p` (normal np_) to the active set with multiplier u: J, R from d_.
  void addToActiveSet(int p, double u);
  /// Removes the active constraint at position `l` of the active set.
  void dropFromActiveSet(int l);

  int n_ = 0, n_eq_ = 0, n_in_ = 0;
  int k_ = 0;                      ///< size of the active set
  int iterations_ = 0;
  Eigen::LLT<Eigen::MatrixXd> llt_;
  Eigen::MatrixXd J_, R_;          ///< J = L^-T Q (n x n); R: k x k upper triangular block used
  Eigen::VectorXd np_, d_, z_, r_, u_, row_norm_;
  std::vector<int> active_;        ///< constraint per active position: equality i -> i, inequality i -> n_eq + i
  std::vector<char> in_active_;    ///< per inequality
};

}  // namespace ehc_control
