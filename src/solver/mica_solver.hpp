// MICA: Modified Iterative Constraint Anticipation (Arikatla, Ortiz, De, Enquobahrie 2016).
// One loop resolves projection constraints and contact together:
//
//   A v = b + G^T lambda,   (I - S) v = z,   0 <= lambda_n  _|_  G_n v + gap / h >= 0,
//   |lambda_t| <= mu lambda_n (isotropic Coulomb friction: a contact's two tangent impulses on a disk)
//
// Each iteration anticipates the contact velocities from the current v with the filtered
// block-diagonal inverse Dt^-1 = S (S D S + I - S)^-1 S, updates lambda by projected
// Gauss-Seidel on B = G Dt^-1 G^T, then sweeps v by modified block Gauss-Seidel with the
// contact impulses on the right-hand side. At a fixed point v and lambda solve the
// complementarity problem above exactly.
#pragma once
#include <vector>

#include "core/colouring.hpp"
#include "core/thread_pool.hpp"
#include "solver/contact_rows.hpp"
#include "solver/projected_system.hpp"

namespace mica {

struct MicaSettings {
  // Stop when the change of v between iterations is below tolerance * max(|v|, |Dt^-1 b|, 1 um/s
  // RMS per node), the change of lambda below tolerance * max(|lambda|, the first anticipated
  // impulse), and the true momentum residual |S (b + G^T lambda - A v)| of every body below
  // tolerance times the size of the terms it balances (per node the largest of |b|, |G^T lambda|,
  // |A v|): the forces a user feels are accurate to the tolerance.
  // Gauss-Seidel that stagnates (stiff bodies, long steps) changes little per sweep far from the
  // solution, so small changes alone prove nothing.
  double tolerance = 1e-8;
  double time_budget_ms = 0;        // > 0: stop when the solve has used this much wall-clock time
  int32_t max_iterations = 200;
  int32_t pgs_sweeps = 1;           // PGS sweeps over the contact rows per iteration
  bool paper_norm = false;          // stop on the 2-norm of the change of (v, lambda) instead
  double relaxation = 1.0;          // MBGS over-relaxation omega in (0, 2); 1 is the paper's Gauss-Seidel
  // Not null (and every body coloured): the MBGS sweep runs colour by colour, a colour's nodes on
  // the pool's threads. Null: the paper's sweep in node order.
  ThreadPool* pool = nullptr;
  // Factored sweep, co-rotational bodies: refactor the current system once a solve has used this
  // many conjugate-gradient iterations (0: never).
  int32_t refactor_after = 0;
};

// One body's system as the solver sees it. v holds the warm start and receives the result.
struct MicaBody {
  const BlockPattern* pattern;
  const BlockValues* A;
  const Vec3List* b;
  const Projection* projection;
  Vec3List* v;
  const std::vector<double>* node_mass = nullptr;  // kg per node: the residual's floor (none if null)
  Vec3List contact_impulse;  // out: G^T lambda per node, N s
  const Colouring* colours = nullptr;  // node blocks coupled by no block of A share a colour (node_colouring.hpp)
};

struct MicaReport : SolveReport {
  double velocity_change = 0;  // last change of v, relative to its scale (see MicaSettings)
  double impulse_change = 0;   // last change of lambda, relative to its scale
  double paper_change = 0;     // last 2-norm of the change of (v, lambda), the paper's test
  double momentum_residual = 0;  // last true residual, relative (see MicaSettings; NaN if never checked)
  int32_t refactorizations = 0;  // factored sweep: factorizations of the current system during the solve
};

class MicaSolver {
 public:
  // lambda: in, the warm start (projected onto its bounds); out, the impulses (N s) per row.
  MicaReport solve(std::vector<MicaBody>& bodies, const ContactRows& rows, const MicaSettings& settings,
                   std::vector<double>& lambda);
  // B_rr of the last solve, per row: the compliance each row sees (its diagonal of G Dt^-1 G^T).
  const std::vector<double>& row_diagonal() const { return diag_; }

 // |S (b + G^T lambda - A v)| / max(|S b|, |S G^T lambda|, |S A v|, |S M v|, 1 um/s of momentum
  // per node), with M lumped and G^T lambda from MicaBody::contact_impulse.
  static double momentum_residual(const std::vector<MicaBody>& bodies);

 private:
  void coloured_sweep(std::vector<MicaBody>& bodies, double relaxation, ThreadPool& pool, double& dv2, double& v2);
  double anticipated_velocity(const std::vector<MicaBody>& bodies, const ContactRows& rows, size_t r) const;
  void update_tangents(const ContactRows& rows, size_t r, std::vector<double>& lambda);

  std::vector<std::vector<Mat3>> inv_diag_;  // per body, per node: Dt_i^-1
  std::vector<Vec3> g_;                      // per row term: coef Dt^-1 d
  std::vector<double> diag_, c_;             // per row: B_rr, anticipated velocity
  std::vector<double> pair_step_;            // per first tangent row: the tangent pair's step length
  std::vector<std::vector<Vec3>> u_;         // per body, per node: Dt^-1 G^T lambda
  std::vector<double> lambda_old_;
  std::vector<std::array<double, 2>> block_sums_;  // coloured sweep: |dv|^2 and |v|^2 per block, in sweep order
};

}  // namespace mica
