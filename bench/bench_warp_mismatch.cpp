// SPDX-License-Identifier: Apache-2.0
// What a factor of an earlier step misses on the nidus scene, and whether correcting it on a few
// nodes would help: the preconditioner P = Q A_ref Q^T (A_ref the system of 1, 5 or 50 steps
// earlier, Q the node rotations since), with the blocks among the M nodes whose rows changed most
// replaced by the current A, factored exactly; conjugate gradients on the current A from a random
// right-hand side to 1e-7 count what is left. Scene as bench_nidus (the tool pressed 2.5 mm at
// 10 mm/s, then +- 1 mm at 1 Hz; 51 steps of 10 ms; MICA factored sweep at 1e-6).
//
// usage: bench_warp_mismatch [mesh]
//   OMP_THREAD_LIMIT=1 OPENBLAS_NUM_THREADS=1 build/bench/bench_warp_mismatch data/nidus/nidus.msh
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <string>

#include "mesh/mesh_io.hpp"
#include "solver/direct_solver.hpp"
#include "solver/pcg.hpp"
#include "world/world.hpp"
#include "cli.h"
using namespace mica;

namespace {
// An exact solve with a factor, as a preconditioner.
struct Exact : Preconditioner {
  DirectSolver* d = nullptr;
  Eigen::MatrixXd x;
  void apply(const Vec3List& r, Vec3List& z) override {
    d->solve_raw(flat(r), x);
    z.resize(r.size());
    flat(z) = x.col(0);
  }
};
}  // namespace

static const char kUsage[] =
    "usage: bench_warp_mismatch [mesh]\n"
    "What a factor of an earlier step misses on the nidus scene, and what correcting it on a few nodes\n"
    "would give (conjugate-gradient iterations to 1e-7 with each preconditioner).\n"
    "  mesh    a .msh or .node/.ele file (default data/nidus/nidus.msh)\n"
    "  --help  this text\n";

int main(int argc, char** argv) {
  const int cli = cli_check(argc, argv, kUsage, NULL);
  if (cli >= 0) return cli;
  const std::string path = argc > 1 ? argv[1] : "data/nidus/nidus.msh";
  std::printf("# command: OMP_THREAD_LIMIT=1 OPENBLAS_NUM_THREADS=1 build/bench/bench_warp_mismatch %s\n",
              path.c_str());
  WorldSettings ws;
  ws.solver = SolverKind::Mica;
  ws.mica_sweep = MicaSweep::Factored;
  ws.tolerance = 1e-6;
  ws.max_iterations = 100000;
  ws.gravity = Vec3::Zero();
  World w(ws);
  BodySettings bs;
  bs.material = {1e4, 0.4, 1000};
  bs.rayleigh_alpha = 2;
  Id id = w.add_body(load_mesh(path), bs, Vec3::Zero(), Vec3::Zero());
  const Body& b = w.body(id);
  Vec3 lo = Vec3::Constant(1e9), hi = -lo, c = Vec3::Zero();
  for (auto& p : b.fem.rest) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
    c += p / b.fem.rest.size();
  }
  std::vector<int32_t> held;
  for (int i = 0; i < (int)b.fem.rest.size(); ++i)
    if (b.fem.rest[i].y() <= lo.y() + 0.2 * (hi.y() - lo.y())) held.push_back(i);
  w.add_lpc(id, held, LpcSpec{});
  double top = -1e9;
  for (auto& p : b.fem.rest)
    if (std::hypot(p.x() - c.x(), p.z() - c.z()) < 1.5e-3) top = std::max(top, p.y());
  double R = 0.002, y0 = top + R + 0.0005;
  Tool t;
  t.radius = R;
  t.margin = 0.0005;
  t.position = Vec3(c.x(), y0, c.z());
  Id tool = w.add_tool(t);
  double dt = 0.01, depth = 0.0025, speed = 0.01, wob = 0.001;
  const int K1 = 50;
  std::map<int, std::pair<BlockValues, std::vector<Mat3>>> saved;
  std::vector<Mat3> Rn;  // the node rotations the last solve warped its factor with
  for (int k = 0; k <= K1; ++k) {
    double tt = (k + 1) * dt, tin = depth / speed;
    double trav = tt < tin ? speed * tt : depth + wob * std::sin(2 * M_PI * (tt - tin));
    w.set_tool_pose(tool, Vec3(c.x(), y0 - trav, c.z()), Eigen::Quaterniond::Identity());
    w.step(dt);
    compute_node_rotations(b.fem, b.rotations(), Rn);
    if (k == K1 - 1 || k == K1 - 5 || k == 0) saved[K1 - k] = {b.A, Rn};
  }
  const BlockPattern& p = b.fem.pattern;
  const int n = p.rows;
  for (auto& [lag, ref] : saved) {
    const BlockValues& Ar = ref.first;
    const std::vector<Mat3>& Rr = ref.second;
    std::vector<Mat3> Q(n);
    for (int i = 0; i < n; ++i) Q[i] = Rn[i] * Rr[i].transpose();
    BlockValues P(Ar.size());
    std::vector<double> e(n, 0.0);
    for (int i = 0; i < n; ++i)
      for (int k = p.row_start[i]; k < p.row_start[i + 1]; ++k) {
        int j = p.col[k];
        P[k] = Q[i] * Ar[k] * Q[j].transpose();
        e[i] += (b.A[k] - P[k]).squaredNorm();
      }
    int diag_k = 0;
    for (int i = 0; i < n; ++i) {
      for (int k = p.row_start[i]; k < p.row_start[i + 1]; ++k)
        if (p.col[k] == i) diag_k = k;
      e[i] = std::sqrt(e[i]) / b.A[diag_k].norm();
      if (b.projection.active() && b.projection.is_constrained[i]) e[i] = 0;
    }
    std::vector<int> order(n);
    for (int i = 0; i < n; ++i) order[i] = i;
    std::sort(order.begin(), order.end(), [&](int a, int c) { return e[a] > e[c]; });
    std::printf("lag %d steps: worst row mismatch %.3g, 10th %.3g, 30th %.3g, 100th %.3g, 300th %.3g\n", lag,
                e[order[0]], e[order[9]], e[order[29]], e[order[99]], e[order[299]]);
    for (int m : {0, 10, 30, 100, 300, 1000}) {
      std::vector<char> inM(n, 0);
      for (int q = 0; q < m; ++q) inM[order[q]] = 1;
      BlockValues Ap = P;
      for (int i = 0; i < n; ++i)
        for (int k = p.row_start[i]; k < p.row_start[i + 1]; ++k)
          if (inM[i] && inM[p.col[k]]) Ap[k] = b.A[k];
      DirectSolver d;
      d.analyze(p);
      try {
        d.factorize(ProjectedSystem{p, Ap, b.projection});
      } catch (...) {
        std::printf("  M=%d: not positive definite\n", m);
        continue;
      }
      Exact pre;
      pre.d = &d;
      PcgSolver pcg;
      pcg.set_preconditioner(&pre);
      pcg.configure(1e-7, 1000);
      Vec3List rhs(n), v(n, Vec3::Zero());
      for (int i = 0; i < n; ++i) rhs[i] = Vec3::Random();
      Projection pr = b.projection;
      for (int i : pr.nodes) pr.z[i].setZero();
      SolveReport r = pcg.solve(ProjectedSystem{p, b.A, pr}, rhs, v);
      std::printf("  M = %4d nodes: PCG %d iterations to 1e-7 (converged %d)\n", m, r.iterations, int(r.converged));
    }
  }
}
