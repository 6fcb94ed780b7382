// SPDX-License-Identifier: Apache-2.0
// CHOLMOD on a body's velocity system: simplicial LDL^T against supernodal LL^T (what
// DirectSolver and the factored sweep use), analysis, numeric factorization and solves with 1
// and 3 right-hand sides, on a mesh file (default: the nidus mesh). The system is that of the
// body's first step (co-rotational, E = 1e4 Pa, nu = 0.4, rho = 1000, Rayleigh alpha = 2,
// dt = 10 ms, no constraints). Each figure is the best of 5 (factorizations) or 20 (solves).
// Then DirectSolver's own factor, with no node held and with the lowest fifth held as in
// bench_nidus (the held nodes' couplings are left out of it): its ordering, size and analysis, a
// solve pair by hand in double and in single precision (the factored sweep's preconditioner), and
// the half columns of 25 nodes (best of 10).
//
// usage: bench_factor [mesh | cube:N]
//   OPENBLAS_NUM_THREADS=1 taskset -c 1 build/bench/bench_factor data/nidus/nidus.msh
#include <Eigen/CholmodSupport>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "mesh/mesh_io.hpp"
#include "solver/direct_solver.hpp"
#include "solver/supernodal_solve.hpp"
#include "world/world.hpp"
#include "cli.h"

using namespace mica;
using Clock = std::chrono::steady_clock;

namespace {

double ms_since(Clock::time_point t) { return std::chrono::duration<double, std::milli>(Clock::now() - t).count(); }

template <class Factor>
void time_factor(const char* name, Factor& f, const Eigen::SparseMatrix<double>& lower) {
  auto t = Clock::now();
  f.analyzePattern(lower);
  const double analyse = ms_since(t);
  // CHOLMOD's own counts from the analysis (its default ordering: AMD, METIS only if AMD fills a lot).
  std::printf("%-22s %.3g M nonzeros in L, %.3g flops per factorization\n", name, 1e-6 * f.cholmod().lnz,
              f.cholmod().fl);
  double factor = 1e300, solve1 = 1e300, solve3 = 1e300;
  for (int k = 0; k < 5; ++k) {
    t = Clock::now();
    f.factorize(lower);
    factor = std::min(factor, ms_since(t));
  }
  const Eigen::VectorXd b = Eigen::VectorXd::Random(lower.rows());
  const Eigen::MatrixXd B = Eigen::MatrixXd::Random(lower.rows(), 3);
  Eigen::VectorXd x;
  Eigen::MatrixXd X;
  for (int k = 0; k < 20; ++k) {
    t = Clock::now();
    x = f.solve(b);
    solve1 = std::min(solve1, ms_since(t));
    t = Clock::now();
    X = f.solve(B);
    solve3 = std::min(solve3, ms_since(t));
  }
  std::printf("%-22s analyse %7.2f ms  factor %8.2f ms  solve 1 rhs %6.3f ms  3 rhs %6.3f ms  %s\n", name, analyse,
              factor, solve1, solve3, f.info() == Eigen::Success ? "ok" : "FAILED");
}

}  // namespace

static const char kUsage[] =
    "usage: bench_factor [mesh]\n"
    "CHOLMOD's simplicial LDL^T against supernodal LL^T on a body's first velocity system\n"
    "(co-rotational, E = 1e4 Pa, nu = 0.4, alpha = 2, dt = 10 ms): analysis, factorization, solves.\n"
    "  mesh    a .msh or .node/.ele file (default data/nidus/nidus.msh), or cube:N, the 0.1 m cube of\n"
    "          N^3 cubes x 6 tets of bench_nidus --scaling (cube:18 is its 35k-tet box)\n"
    "  --help  this text\n"
    "Run it as: OPENBLAS_NUM_THREADS=1 taskset -c 1 build/bench/bench_factor data/nidus/nidus.msh\n";

int main(int argc, char** argv) {
  const int cli = cli_check(argc, argv, kUsage, NULL);
  if (cli >= 0) return cli;
  const std::string path = argc > 1 ? argv[1] : "data/nidus/nidus.msh";
  WorldSettings ws;
  ws.gravity = Vec3::Zero();
  World world(ws);
  BodySettings bs;
  bs.material = {1e4, 0.4, 1000};
  bs.rayleigh_alpha = 2;
  int cube = 0;
  if (path.rfind("cube:", 0) == 0 && !cli_int(argv[0], "cube:N", path.c_str() + 5, 1, 60, &cube)) return 2;
  const TetMesh mesh = cube ? make_box_grid(Vec3(0, 0, 0), Vec3(0.1, 0.1, 0.1), {cube, cube, cube}, 6) : load_mesh(path);
  const Id id = world.add_body(mesh, bs, Vec3::Zero(), Vec3::Zero());
  world.step(0.01);  // assembles A
  const Body& body = world.body(id);
  const BlockPattern& p = body.fem.pattern;
  std::vector<Eigen::Triplet<double>> entries;
  for (int32_t i = 0; i < p.rows; ++i)
    for (int32_t k = p.row_start[i]; k < p.row_start[i + 1]; ++k)
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c)
          if (3 * i + r >= 3 * p.col[k] + c) entries.emplace_back(3 * i + r, 3 * p.col[k] + c, body.A[k](r, c));
  Eigen::SparseMatrix<double> lower(3 * p.rows, 3 * p.rows);
  lower.setFromTriplets(entries.begin(), entries.end());
  std::printf("# bench_factor: %s: %d nodes (%d DOF), %zu tets; %ld stored entries (lower triangle)\n", path.c_str(),
              p.rows, 3 * p.rows, body.tets.size(), long(lower.nonZeros()));
  std::printf("# command: OPENBLAS_NUM_THREADS=1 taskset -c 1 build/bench/bench_factor %s\n", path.c_str());
  {
    Eigen::CholmodSimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower> f;
    time_factor("simplicial LDL^T", f, lower);
  }
  {
    Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>, Eigen::Lower> f;
    time_factor("supernodal LL^T (AMD)", f, lower);
  }
  // DirectSolver leaves the couplings of held nodes out of its factor: free, then held as the
  // nidus scene is.
  double lo = 1e300, hi = -1e300;
  for (const Vec3& x : body.x) lo = std::min(lo, x.y()), hi = std::max(hi, x.y());
  for (const bool held : {false, true}) {
    Projection projection;
    projection.reset(p.rows);
    for (int32_t i = 0; held && i < p.rows; ++i)
      if (body.x[size_t(i)].y() <= lo + 0.2 * (hi - lo)) projection.constrain(i, Mat3::Identity(), Vec3::Zero());
    // The factored sweep's solve pair, one right-hand side: cholmod_solve2 against the
    // hand-written supernodal solve (solver/supernodal_solve.hpp) in double, in single and in
    // half precision (where this CPU has F16C), taken in turn, best of 50 each.
    DirectSolver d, dh;
    d.set_copy(SupernodalSolve::Copy::Single);
    dh.set_copy(SupernodalSolve::Copy::Half);
    const auto t_analyse = Clock::now();
    d.analyze(p, &projection);
    const double analyse = ms_since(t_analyse);
    // Again with the ordering known: what a new set of held nodes (a grasp) costs.
    const auto t_again = Clock::now();
    d.analyze(p, &projection);
    const double again = ms_since(t_again);
    dh.analyze(p, &projection);
    dh.factorize(ProjectedSystem{p, body.A, projection});
    double factor = 1e300;
    for (int k = 0; k < 5; ++k) {
      const auto t = Clock::now();
      d.factorize(ProjectedSystem{p, body.A, projection});
      factor = std::min(factor, ms_since(t));
    }
    std::printf("DirectSolver, %s:\n", held ? "the lowest fifth held (bench_nidus's scene)" : "no node held");
    std::printf("                       ordering %s (AMD or nested dissection, the lesser fill), %.3g M stored "
                "entries (%.3g M nonzeros in L), %.3g flops per factorization, analyse %.2f ms (again, the ordering "
                "known: %.2f ms), factor %.2f ms\n",
                d.ordering() == CHOLMOD_NESDIS ? "NESDIS" : d.ordering() == CHOLMOD_AMD ? "AMD" : "other",
                1e-6 * double(d.factor_entries()), 1e-6 * d.factor_nonzeros(), d.factor_flops(), analyse, again, factor);
    const Eigen::VectorXd b = Eigen::VectorXd::Random(3 * p.rows);
    Eigen::MatrixXd x1, x2;
    Eigen::VectorXd x3, x4;
    double cholmod = 1e300, by_hand = 1e300, single = 1e300, half = 1e300;
    for (int k = 0; k < 50; ++k) {
      auto t = Clock::now();
      d.solve_raw_cholmod(b, x1);
      cholmod = std::min(cholmod, ms_since(t));
      t = Clock::now();
      d.solve_raw(b, x2);
      by_hand = std::min(by_hand, ms_since(t));
      t = Clock::now();
      d.solve_one(b, x3, true);
      single = std::min(single, ms_since(t));
      t = Clock::now();
      dh.solve_one(b, x4, true);
      half = std::min(half, ms_since(t));
    }
    std::printf("  solve pair, 1 rhs:   cholmod_solve2 %.3f ms; by hand %.3f ms (%.2fx, difference %.1e); single "
                "precision %.3f ms (%.2fx, difference %.1e)\n",
                cholmod, by_hand, by_hand / cholmod, (x1 - x2).norm() / x1.norm(), single, single / cholmod,
                (x1.col(0) - x3).norm() / x1.norm());
    std::printf("                       half precision %.3f ms (%.2fx single, difference %.1e)%s\n", half,
                half / single, (x1.col(0) - x4).norm() / x1.norm(),
                dh.by_hand()->half() ? "" : " (no half copy: this CPU lacks F16C, or the probe refused it)");
    // The half columns of 25 nodes spread over the body (a contact set's worth: what the factored
    // sweep makes for a new factor's contact nodes, in the background or in the step), from the
    // copy the sweep keeps (the half one where the CPU has it).
    constexpr int kNodes = 25;
    std::vector<SupernodalSolve::HalfColumns> columns(kNodes);
    double columns_ms = 1e300;
    long rows = 0;
    for (int k = 0; k < 10; ++k) {
      const auto t = Clock::now();
      for (int a = 0; a < kNodes; ++a)
        dh.by_hand()->half_columns(3 * int32_t(int64_t(a) * p.rows / kNodes), columns[size_t(a)]);
      columns_ms = std::min(columns_ms, ms_since(t));
    }
    for (const auto& c : columns) rows += long(c.values.rows());
    std::printf("  half columns:        %d nodes in %.3f ms (%.1f rows each on average), from the %s copy\n", kNodes,
                columns_ms, double(rows) / kNodes, dh.by_hand()->half() ? "half" : "single");
  }
  return 0;
}
