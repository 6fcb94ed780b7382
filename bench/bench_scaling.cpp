// SPDX-License-Identifier: Apache-2.0
// Time per step against tets on one thread and on several, side by side: the scene of
// `bench_nidus --scaling` (a 0.1 m cube of n^3 cubes x 6 tets, E = 2e4 Pa, nu = 0.3, rho = 1000,
// Rayleigh alpha = 2, co-rotational, consistent mass, gravity, base fixed; a 2 cm sphere pressed
// 7 mm in at 0.1 m/s, then 7 mm +- 3 mm at 1 Hz; MICA at tolerance 1e-6, dt = 10 ms), built twice
// per size: WorldSettings::threads = 1 (the serial path, the paper's natural-order sweep) and
// threads = T (parallel rotations and assembly, colour-ordered sweep). The two worlds step in
// turn (which one goes first alternates), so both see the same machine load.
//
// It uses the C++ API (linked against the core objects). Per size it prints the median ms per
// step and per stage (Rotations, Elements, Solve), the mean iterations per step, the Solve time
// per iteration, and the speed-ups T : 1.
//
// usage: bench_scaling [out.csv] [max-tets] [threads] [timed-steps-above-40k]
//          defaults: out/scaling_threads.csv 110000 2 4
//        9 warm-up steps, then 20 timed steps (10 above 10k tets, the last argument above 40k).
// Run it with CHOLMOD's BLAS kept to one thread, on as many CPUs as threads:
//   OPENBLAS_NUM_THREADS=1 taskset -c 0,1 build/bench/bench_scaling out/scaling_threads.csv 110000 2
#include <sched.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "world/world.hpp"
#include "cli.h"

using namespace mica;

namespace {

double median(std::vector<double> v) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

std::string machine() {
  std::string model = "unknown CPU";
  std::ifstream cpu("/proc/cpuinfo");
  for (std::string line; std::getline(cpu, line);)
    if (line.rfind("model name", 0) == 0) {
      model = line.substr(line.find(':') + 2);
      break;
    }
  cpu_set_t set;
  CPU_ZERO(&set);
  const int cpus = sched_getaffinity(0, sizeof set, &set) == 0 ? CPU_COUNT(&set) : -1;
  return model + "; this process may run on " + std::to_string(cpus) + " CPU(s)";
}

double load_average() {
  double load = -1;
  std::ifstream f("/proc/loadavg");
  f >> load;
  return load;
}

struct Run {
  std::unique_ptr<World> world;
  Id body = 0, tool = 0;
  std::vector<double> step_ms, rotations_ms, elements_ms, solve_ms;
  int64_t iterations = 0;
  double solve_total_ms = 0;
  int32_t capped = 0;
};

void build(Run& r, int n, int32_t threads) {
  WorldSettings ws;
  ws.solver = SolverKind::Mica;
  ws.mica_sweep = MicaSweep::GaussSeidel;  // the paper's sweep, colour-ordered on several threads
  ws.tolerance = 1e-6;
  ws.max_iterations = 100000;
  ws.threads = threads;
  r.world = std::make_unique<World>(ws);
  BodySettings bs;
  bs.material = {2e4, 0.3, 1000};
  bs.rayleigh_alpha = 2;
  r.body = r.world->add_body(make_box_grid(Vec3(0, 0, 0), Vec3(0.1, 0.1, 0.1), {n, n, n}, 6), bs, Vec3::Zero(),
                             Vec3::Zero());
  std::vector<int32_t> base;
  const Body& b = r.world->body(r.body);
  for (int32_t i = 0; i < b.fem.node_count(); ++i)
    if (b.fem.rest[i].y() <= 1e-9) base.push_back(i);
  r.world->add_lpc(r.body, base, LpcSpec{});
  Tool t;
  t.radius = 0.02;
  t.margin = 0.002;
  t.position = Vec3(0.05, 0.1 + 0.02 + 0.001, 0.05);
  r.tool = r.world->add_tool(t);
  r.world->step(0.01);  // the first step allocates the solver's buffers
}

void step(Run& r, int k, bool timed) {
  const double dt = 0.01, depth = 0.007, speed = 0.1, wobble = 0.003, y0 = 0.1 + 0.02 + 0.001;
  const double t = (k + 1) * dt, t_in = depth / speed;
  const double travel = t < t_in ? speed * t : depth + wobble * std::sin(2 * M_PI * (t - t_in));
  r.world->set_tool_pose(r.tool, Vec3(0.05, y0 - travel, 0.05), Eigen::Quaterniond::Identity());
  const auto start = std::chrono::steady_clock::now();
  r.world->step(dt);
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  if (!timed) return;
  const WorldStats& s = r.world->stats();
  r.step_ms.push_back(ms);
  r.rotations_ms.push_back(s.stages[size_t(Stage::Rotations)].ms_last_step);
  r.elements_ms.push_back(s.stages[size_t(Stage::Elements)].ms_last_step);
  r.solve_ms.push_back(s.stages[size_t(Stage::Solve)].ms_last_step);
  r.solve_total_ms += s.stages[size_t(Stage::Solve)].ms_last_step;
  r.iterations += s.solver_iterations;
  if (!s.converged) ++r.capped;
}

}  // namespace

static const char kUsage[] =
    "usage: bench_scaling [out.csv] [max-tets] [threads] [timed-steps-above-40k]\n"
    "Time per step against tets on one thread and on several, side by side: a 0.1 m cube of n^3 x 6\n"
    "tets pressed by a 2 cm sphere, MICA (Gauss-Seidel sweep) at tolerance 1e-6, dt = 10 ms.\n"
    "  out.csv                where the table goes (default out/scaling_threads.csv)\n"
    "  max-tets               the largest cube (default 110000)\n"
    "  threads                the parallel world's threads (default 2)\n"
    "  timed-steps-above-40k  timed steps of the largest cubes (default 4)\n"
    "  --help                 this text\n"
    "Run it as: OPENBLAS_NUM_THREADS=1 taskset -c 0,1 build/bench/bench_scaling out/scaling_threads.csv 110000 2\n";

int main(int argc, char** argv) {
  const int cli = cli_check(argc, argv, kUsage, NULL);
  if (cli >= 0) return cli;
  const std::string csv_path = argc > 1 ? argv[1] : "out/scaling_threads.csv";
  int max_tets = 110000, threads = 2, large_steps = 4;
  if ((argc > 2 && !cli_int(argv[0], "max-tets", argv[2], 1, 100000000, &max_tets)) ||
      (argc > 3 && !cli_int(argv[0], "threads", argv[3], 2, 1024, &threads)) ||
      (argc > 4 && !cli_int(argv[0], "timed-steps-above-40k", argv[4], 1, 1000000, &large_steps)))
    return 2;
  if (!cli_make_parent(argv[0], csv_path.c_str())) return 1;
  FILE* csv = std::fopen(csv_path.c_str(), "w");
  if (!csv) {
    std::fprintf(stderr, "cannot write %s\n", csv_path.c_str());
    return 1;
  }
  const std::string m = machine();
  std::fprintf(csv, "# bench_scaling: %s; load average %.2f at the start\n", m.c_str(), load_average());
  std::fprintf(csv,
               "cells,nodes,tets,node_colours,element_colours,threads,steps,ms_median,rotations_ms,elements_ms,"
               "solve_ms,iterations,solve_ms_per_iteration,capped\n");
  std::printf("# bench_scaling: %s; load average %.2f at the start\n", m.c_str(), load_average());
  std::printf("# command: OPENBLAS_NUM_THREADS=1 taskset -c 0,1 build/bench/bench_scaling %s %d %d %d\n",
              csv_path.c_str(), max_tets, threads, large_steps);
  std::printf("# medians over the timed steps; 'it' = mean MICA iterations per step; speed-up = 1 thread / %d\n",
              threads);
  std::printf("%5s %7s %7s %6s | %4s %9s %8s %8s %9s %7s %9s | %6s %6s %6s %6s %8s\n", "cells", "nodes", "tets",
              "colour", "thr", "ms/step", "rot ms", "elem ms", "solve ms", "it", "us/it", "step", "rot", "elem",
              "solve", "solve/it");
  const int sizes[] = {6, 8, 11, 14, 18, 22, 26, 30};
  for (int n : sizes) {
    if (6L * n * n * n > max_tets) break;
    Run runs[2];
    build(runs[0], n, 1);
    build(runs[1], n, threads);
    const Body& b = runs[1].world->body(runs[1].body);
    const int tets = int(b.tets.size());
    const int steps = tets > 40000 ? large_steps : tets > 10000 ? 10 : 20, warmup = 9;
    for (int k = 0; k < warmup + steps; ++k)
      for (int j = 0; j < 2; ++j) step(runs[(k + j) % 2], k, k >= warmup);
    double per_it[2];
    for (int j = 0; j < 2; ++j) {
      const Run& r = runs[j];
      const int32_t t = j == 0 ? 1 : threads;
      per_it[j] = r.iterations > 0 ? r.solve_total_ms / double(r.iterations) : NAN;
      std::fprintf(csv, "%d,%d,%d,%d,%d,%d,%d,%.4f,%.4f,%.4f,%.4f,%.1f,%.6f,%d\n", n, b.fem.node_count(), tets,
                   b.node_colours.colours(), b.element_colours.colours(), t, steps, median(r.step_ms),
                   median(r.rotations_ms), median(r.elements_ms), median(r.solve_ms), double(r.iterations) / steps,
                   per_it[j], r.capped);
    }
    std::fflush(csv);
    for (int j = 0; j < 2; ++j) {
      const Run& r = runs[j];
      if (j == 0)
        std::printf("%5d %7d %7d %2d/%-3d | ", n, b.fem.node_count(), tets, b.node_colours.colours(),
                    b.element_colours.colours());
      else
        std::printf("%5s %7s %7s %6s | ", "", "", "", "");
      std::printf("%4d %9.3f %8.3f %8.3f %9.3f %7.1f %9.2f |", j == 0 ? 1 : threads, median(r.step_ms),
                  median(r.rotations_ms), median(r.elements_ms), median(r.solve_ms), double(r.iterations) / steps,
                  1e3 * per_it[j]);
      if (j == 1)
        std::printf(" %6.2f %6.2f %6.2f %6.2f %8.2f", median(runs[0].step_ms) / median(r.step_ms),
                    median(runs[0].rotations_ms) / median(r.rotations_ms),
                    median(runs[0].elements_ms) / median(r.elements_ms), median(runs[0].solve_ms) / median(r.solve_ms),
                    per_it[0] / per_it[1]);
      std::printf("\n");
    }
    std::fflush(stdout);
  }
  std::printf("# load average %.2f at the end\n", load_average());
  std::fclose(csv);
  return 0;
}
