// SPDX-License-Identifier: Apache-2.0
// Per-stage counters and timings of the step, and the solver's report.
#pragma once
#include <array>
#include <chrono>
#include <cstdint>

namespace mica {

// The stages of a step (the C header numbers them the same way; the pipeline runs Collide first
// and Forces last).
enum class Stage { Loads, Rotations, Elements, Damping, Constraints, Solve, Integrate, Collide, Forces, Count };
constexpr int kStageCount = int(Stage::Count);

struct StageStats {
  int32_t runs_last_step = 0;
  int32_t unused = 0;
  int64_t runs_total = 0;
  double ms_last_step = 0;
  double ms_total = 0;
};

// StageStats and WorldStats have no padding: saved states copy them as bytes (state_io.cpp).
struct WorldStats {
  int64_t step_count = 0;
  std::array<StageStats, kStageCount> stages{};
  double solver_residual = 0;
  double ms_last_step = 0;
  int32_t solver_iterations = 0;
  bool converged = true;
  bool out_of_time = false;  // a solve stopped at WorldSettings::time_budget_ms
  uint8_t factor_waits = 0;  // of the factorizations, those the step waited for (at most 255)
  uint8_t unused = 0;
  int32_t solver_solves = 0;    // velocity solves (SolveReport::solves, at least 1 per solve)
  int32_t factorizations = 0;   // numeric factorizations made or started in the background
};

// Runs a stage if the plan holds it, timing it into the stats.
class StageRunner {
 public:
  explicit StageRunner(WorldStats& stats) : stats_(stats) {
    for (auto& s : stats_.stages) {
      s.runs_last_step = 0;
      s.ms_last_step = 0;
    }
  }
  template <class F>
  void run(Stage stage, bool planned, F&& f) {
    if (!planned) return;
    const auto start = std::chrono::steady_clock::now();
    f();
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    StageStats& s = stats_.stages[size_t(stage)];
    s.runs_last_step += 1;
    s.runs_total += 1;
    s.ms_last_step += ms;
    s.ms_total += ms;
  }

 private:
  WorldStats& stats_;
};

}  // namespace mica
