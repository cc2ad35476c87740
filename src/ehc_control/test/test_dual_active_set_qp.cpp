// DualActiveSetQp: the controller's QP solver (dual_active_set_qp.h). Solutions are checked
// against the KKT conditions (unique optimum of a strictly convex QP) and against ViSP's
// vpQuadProg on random problems of the controller's shape.
#include "ehc_control/dual_active_set_qp.h"

#include <visp3/core/vpQuadProg.h>

#include <gtest/gtest.h>

#include <fstream>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <vector>

using ehc_control::DualActiveSetQp;
using ehc_control::QpProblem;
using ehc_control::QpSolveResult;

namespace {

QpProblem loadProblem(const std::string& name) {
  std::ifstream f(std::string(EHC_TEST_DIR) + "/data/" + name);
  if (!f) throw std::runtime_error("cannot open test data " + name);
  return QpProblem::read(f);
}

/// The KKT conditions of x with the solver's multipliers: feasibility, lambda >= 0,
/// complementarity, stationarity G x + g + A^T mu + C^T lambda = 0 (mu by least squares).
void expectKkt(const QpProblem& p, const Eigen::VectorXd& x, const DualActiveSetQp& qp, double tol) {
  if (p.A.rows()) {
    EXPECT_LT((p.A * x - p.b).cwiseAbs().maxCoeff(), tol);
  }
  const Eigen::VectorXd slack = p.d - p.C * x;
  if (p.C.rows()) {
    EXPECT_GT(slack.minCoeff(), -tol);
  }
  const Eigen::VectorXd lambda = qp.inequalityMultipliers();
  ASSERT_EQ(lambda.size(), p.C.rows());
  for (Eigen::Index i = 0; i < lambda.size(); ++i) {
    EXPECT_GE(lambda[i], -tol) << "row " << i;
    EXPECT_LT(std::abs(lambda[i] * slack[i]), tol) << "row " << i;
  }
  Eigen::VectorXd grad = p.G * x + p.g + p.C.transpose() * lambda;
  if (p.A.rows()) {
    const Eigen::VectorXd mu = (p.A * p.A.transpose()).ldlt().solve(-p.A * grad);
    grad += p.A.transpose() * mu;
  }
  EXPECT_LT(grad.cwiseAbs().maxCoeff(), tol);
}

/// The controller's shape: diagonal cost, a 6-row task with slack (equalities), velocity and
/// slack bounds, and `obstacles` random damper rows.
QpProblem randomControllerProblem(std::mt19937& rng, int n, int obstacles) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const int nx = n + 6;
  QpProblem p;
  p.G = Eigen::MatrixXd::Zero(nx, nx);
  p.g = Eigen::VectorXd::Zero(nx);
  for (int i = 0; i < nx; ++i) p.G(i, i) = i < n ? 0.001 + 0.05 * (1.0 + u(rng)) : 1.0 + 50.0 * (1.0 + u(rng));
  for (int i = 0; i < n; ++i) p.g[i] = 0.01 * u(rng);
  p.A = Eigen::MatrixXd::Zero(6, nx);
  p.b.resize(6);
  for (int r = 0; r < 6; ++r) {
    for (int k = 0; k < n; ++k) p.A(r, k) = u(rng);
    p.A(r, n + r) = 1.0;
    p.b[r] = 2.0 * u(rng);
  }
  p.C = Eigen::MatrixXd::Zero(2 * nx + obstacles, nx);
  p.d.resize(2 * nx + obstacles);
  for (int i = 0; i < nx; ++i) {
    p.C(2 * i, i) = 1.0;
    p.C(2 * i + 1, i) = -1.0;
    p.d[2 * i] = p.d[2 * i + 1] = i < n ? 0.3 + 0.5 * (1.0 + u(rng)) : 10.0;
  }
  for (int o = 0; o < obstacles; ++o) {
    Eigen::VectorXd a = Eigen::VectorXd::Zero(nx);
    for (int k = 0; k < n; ++k) a[k] = u(rng);
    p.C.row(2 * nx + o) = a.normalized().transpose();
    p.d[2 * nx + o] = 0.2 * (1.0 + u(rng));
  }
  return p;
}

vpMatrix toVisp(const Eigen::MatrixXd& m) {
  vpMatrix v(static_cast<unsigned>(m.rows()), static_cast<unsigned>(m.cols()));
  for (Eigen::Index i = 0; i < m.rows(); ++i)
    for (Eigen::Index j = 0; j < m.cols(); ++j) v[static_cast<unsigned>(i)][static_cast<unsigned>(j)] = m(i, j);
  return v;
}
vpColVector toVispVector(const Eigen::VectorXd& x) {
  vpColVector v(static_cast<unsigned>(x.size()));
  for (Eigen::Index i = 0; i < x.size(); ++i) v[static_cast<unsigned>(i)] = x[i];
  return v;
}

}  // namespace

// Captured from `ehc_experiment poses --method neo_nompbs --sets 4 --per-set 1 --seed 1` (run
// 12, set 3 sideways) when the controller still used vpQuadProg: 14 variables, 6 equality rows
// (TCP task with slack), 40 inequality rows (28 velocity/slack bounds, 12 obstacle dampers).
// vpQuadProg's primal active-set loop cycled on it for ever (from its 7th iteration the active
// set repeated with period 4: obstacle rows 28 and 29 dropped and re-activated in turn with
// zero-length steps). Stored in vpQuadProg's least-squares form |Q x - r|^2 at capture; here
// as G = Q^T Q, g = -Q^T r (same minimiser).
const char* const kCycling = "qp_cycling_poses_neo_nompbs_seed1.txt";

TEST(QpProblem, FileRoundTrips) {
  const QpProblem p = loadProblem(kCycling);
  EXPECT_EQ(p.G.rows(), 14);
  EXPECT_EQ(p.A.rows(), 6);
  EXPECT_EQ(p.C.rows(), 40);
  std::ostringstream os;
  p.write(os);
  std::istringstream is(os.str());
  const QpProblem q = QpProblem::read(is);
  EXPECT_EQ(q.G, p.G);
  EXPECT_EQ(q.C, p.C);
  EXPECT_EQ(q.d, p.d);
  std::istringstream bad("G 2 2\n1 0\n");
  EXPECT_THROW(QpProblem::read(bad), std::runtime_error);
}

// The dual method solves the problem vpQuadProg cycled on, in a few steps, to its KKT point.
TEST(DualActiveSetQp, SolvesTheProblemVpQuadProgCycledOn) {
  const QpProblem p = loadProblem(kCycling);
  DualActiveSetQp qp;
  Eigen::VectorXd x;
  ASSERT_EQ(qp.solve(p, &x, 200), QpSolveResult::Solved);
  EXPECT_LE(qp.iterations(), 30);
  expectKkt(p, x, qp, 1e-8);
  // The obstacle rows that cycled in vpQuadProg are both active at the optimum.
  const std::vector<int> active = qp.activeInequalities();
  EXPECT_NE(std::find(active.begin(), active.end(), 28), active.end());
  EXPECT_NE(std::find(active.begin(), active.end(), 29), active.end());
  // Bounded: fewer steps than it needs give IterationLimit, never a wrong answer.
  const int needed = qp.iterations();
  EXPECT_EQ(qp.solve(p, &x, needed - 1), QpSolveResult::IterationLimit);
  EXPECT_EQ(qp.iterations(), needed - 1);
}

// Random problems of the controller's shape against ViSP's vpQuadProg (which the controller
// used before): the dual method's solution is optimal (KKT) and never worse than vpQuadProg's;
// where vpQuadProg's is optimal too, both agree. vpQuadProg returns a feasible but suboptimal
// point on some of these problems (39 of the 200 here, objective up to 3x the optimum's).
TEST(DualActiveSetQp, OptimalAndNeverWorseThanVpQuadProgOnRandomProblems) {
  std::mt19937 rng(7);
  DualActiveSetQp qp;
  int with_active = 0, agree = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const QpProblem p = randomControllerProblem(rng, trial % 2 ? 8 : 10, trial % 11);
    Eigen::VectorXd x;
    ASSERT_EQ(qp.solve(p, &x, 200), QpSolveResult::Solved) << "trial " << trial;
    expectKkt(p, x, qp, 1e-8);
    with_active += !qp.activeInequalities().empty();
    // vpQuadProg's least-squares form: |Q x - r|^2 with Q = G^(1/2) (diagonal), r = -Q^-1 g.
    const Eigen::VectorXd q = p.G.diagonal().cwiseSqrt();
    vpQuadProg reference;
    vpColVector x_visp;
    ASSERT_TRUE(reference.solveQP(toVisp(q.asDiagonal().toDenseMatrix()), toVispVector(-p.g.cwiseQuotient(q)),
                                  toVisp(p.A), toVispVector(p.b), toVisp(p.C), toVispVector(p.d), x_visp, 1e-6));
    Eigen::VectorXd x_ref(x.size());
    for (Eigen::Index i = 0; i < x.size(); ++i) x_ref[i] = x_visp[static_cast<unsigned>(i)];
    EXPECT_LT((p.C * x_ref - p.d).maxCoeff(), 1e-9) << "trial " << trial;
    const auto cost = [&p](const Eigen::VectorXd& y) { return 0.5 * y.dot(p.G * y) + p.g.dot(y); };
    EXPECT_LE(cost(x), cost(x_ref) + 1e-12 * (1.0 + std::abs(cost(x_ref)))) << "trial " << trial;
    if (cost(x_ref) - cost(x) < 1e-12 * (1.0 + std::abs(cost(x)))) {
      ++agree;
      EXPECT_LT((x - x_ref).cwiseAbs().maxCoeff(), 1e-6) << "trial " << trial;
    }
  }
  EXPECT_GT(with_active, 150);  // the bounds and dampers bind in most trials
  EXPECT_EQ(agree, 161);
}

TEST(DualActiveSetQp, UnconstrainedAndBoundedSolutions) {
  Eigen::MatrixXd G = Eigen::Vector3d(1.0, 2.0, 4.0).asDiagonal();
  const Eigen::Vector3d g(-1.0, -4.0, 8.0);
  DualActiveSetQp qp;
  Eigen::VectorXd x;
  const Eigen::MatrixXd none(0, 3);
  ASSERT_EQ(qp.solve(G, g, none, Eigen::VectorXd(0), none, Eigen::VectorXd(0), &x, 10), QpSolveResult::Solved);
  EXPECT_TRUE(x.isApprox(Eigen::Vector3d(1.0, 2.0, -2.0)));
  EXPECT_EQ(qp.iterations(), 0);
  // x1 <= 1, -x2 <= 1 (x2 >= -1), x0 + x1 + x2 = 1
  Eigen::MatrixXd C(2, 3), A(1, 3);
  C << 0, 1, 0, 0, 0, -1;
  A << 1, 1, 1;
  ASSERT_EQ(qp.solve(G, g, A, Eigen::VectorXd::Ones(1), C, Eigen::Vector2d(1.0, 1.0), &x, 10), QpSolveResult::Solved);
  const QpProblem p{G, A, C, g, Eigen::VectorXd::Ones(1), Eigen::Vector2d(1.0, 1.0)};
  expectKkt(p, x, qp, 1e-12);
  EXPECT_NEAR(x[1], 1.0, 1e-12);
  EXPECT_NEAR(x[2], -1.0, 1e-12);
  EXPECT_NEAR(x[0], 1.0, 1e-12);
}

// Duplicate and near-duplicate rows (the degeneracy of obstacle rows of links sharing a
// point) and a dependent but consistent equality.
TEST(DualActiveSetQp, DegenerateRows) {
  const Eigen::MatrixXd G = Eigen::Matrix2d::Identity();
  const Eigen::Vector2d g(-2.0, -2.0);  // unconstrained minimum (2, 2)
  Eigen::MatrixXd C(4, 2);
  C << 1, 1, 1, 1, 1, 1 + 1e-9, 2, 2;  // four copies of x0 + x1 <= 1
  const Eigen::Vector4d d(1.0, 1.0, 1.0, 2.0);
  Eigen::MatrixXd A(2, 2);
  A << 1, -1, 2, -2;  // x0 = x1 twice
  DualActiveSetQp qp;
  Eigen::VectorXd x;
  ASSERT_EQ(qp.solve(G, g, A, Eigen::Vector2d::Zero(), C, d, &x, 50), QpSolveResult::Solved);
  EXPECT_NEAR(x[0], 0.5, 1e-8);
  EXPECT_NEAR(x[1], 0.5, 1e-8);
  // Inconsistent dependent equalities.
  EXPECT_EQ(qp.solve(G, g, A, Eigen::Vector2d(0.0, 1.0), C, d, &x, 50), QpSolveResult::Infeasible);
}

TEST(DualActiveSetQp, InfeasibleAndBadInput) {
  const Eigen::MatrixXd G = Eigen::Matrix2d::Identity();
  const Eigen::Vector2d g(0.3, -0.2);
  Eigen::MatrixXd C(3, 2);
  C << 1, 0, -1, 0, 0, 1;  // x0 <= -1 and x0 >= 1
  DualActiveSetQp qp;
  Eigen::VectorXd x;
  const Eigen::MatrixXd none(0, 2);
  EXPECT_EQ(qp.solve(G, g, none, Eigen::VectorXd(0), C, Eigen::Vector3d(-1.0, -1.0, 5.0), &x, 50),
            QpSolveResult::Infeasible);
  Eigen::MatrixXd zero_row = Eigen::MatrixXd::Zero(1, 2);  // 0 <= -1
  EXPECT_EQ(qp.solve(G, g, none, Eigen::VectorXd(0), zero_row, -Eigen::VectorXd::Ones(1), &x, 50),
            QpSolveResult::Infeasible);
  EXPECT_THROW(qp.solve(-G, g, none, Eigen::VectorXd(0), C, Eigen::Vector3d::Zero(), &x, 50), std::invalid_argument);
  EXPECT_THROW(qp.solve(G, g, none, Eigen::VectorXd(0), C, Eigen::Vector2d::Zero(), &x, 50), std::invalid_argument);
  EXPECT_THROW(qp.solve(G, g, none, Eigen::VectorXd(0), C, Eigen::Vector3d::Zero(), &x, 0), std::invalid_argument);
  EXPECT_EQ(ehc_control::toString(QpSolveResult::IterationLimit), "iteration limit");
}

// The factory behind the controller's qp_solver parameter: the dual active-set solver by name
// (the same solution through the QpSolver interface as called directly), an unknown name an
// error that lists the known ones.
TEST(QpSolverFactory, MakesTheDualActiveSetSolverAndRejectsUnknownNames) {
  EXPECT_EQ(ehc_control::qpSolverNames(), std::vector<std::string>{"dual_active_set"});
  const std::unique_ptr<ehc_control::QpSolver> solver = ehc_control::makeQpSolver("dual_active_set");
  ASSERT_TRUE(solver);
  EXPECT_EQ(solver->name(), "dual_active_set");
  const QpProblem p = loadProblem(kCycling);
  Eigen::VectorXd through_interface, direct;
  ASSERT_EQ(solver->solve(p, &through_interface, 200), QpSolveResult::Solved);
  DualActiveSetQp qp;
  ASSERT_EQ(qp.solve(p.G, p.g, p.A, p.b, p.C, p.d, &direct, 200), QpSolveResult::Solved);
  EXPECT_EQ(through_interface, direct);
  EXPECT_EQ(solver->iterations(), qp.iterations());
  for (const std::string bad : {"", "qpoases", "Dual_Active_Set"}) {
    try {
      ehc_control::makeQpSolver(bad);
      FAIL() << bad;
    } catch (const std::invalid_argument& e) {
      EXPECT_EQ(std::string(e.what()), "[QpSolverFactory] unknown QP solver '" + bad + "' (known: dual_active_set)");
    }
  }
}
