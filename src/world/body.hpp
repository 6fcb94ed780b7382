// A deformable (or static) body: its finite-element model, its state, and the per-step
// work arrays, sized once at creation so that stepping does not allocate.
#pragma once
#include <string>
#include <vector>

#include "collision/bvh.hpp"
#include "collision/pseudo_normals.hpp"
#include "core/colouring.hpp"
#include "fem/fem_model.hpp"
#include "fem/rotation_stiffness.hpp"
#include "solver/direct_solver.hpp"
#include "solver/pcg.hpp"
#include "solver/lagged_factor.hpp"
#include "solver/projection.hpp"

namespace mica {

struct BodySettings {
  Material material;
  double rayleigh_alpha = 0;  // 1/s
  double rayleigh_beta = 0;   // s
  MassKind mass = MassKind::Consistent;
  bool corotational = true;
  bool is_static = false;
};

struct Body {
  Body(const TetMesh& mesh, const BodySettings& settings, const std::string& name);

  BodySettings settings;
  std::string name;            // "body 0x..." in messages
  FemModel fem;
  std::vector<Tet> tets;
  std::vector<Tri> surface;
  std::vector<int32_t> surface_node_list;  // candidates for contact
  TriangleBvh bvh;                         // over the surface triangles, refit every step
  SurfacePseudoNormals pseudo_normals;     // of the surface, updated with the tree
  double surface_edge = 0;                 // m, mean surface edge length: the deepest penetration looked for

  // State.
  Vec3List x, v;
  Vec3List node_forces;        // persistent user loads, N
  bool has_node_forces = false;
  uint64_t lpc_version = 0;    // bumped when a constraint on this body is added or removed

  // Per-step work.
  std::vector<Mat3> R;         // element rotations the step is linearised with
  std::vector<Mat3> R_end;     // rotations of x_end (computed after the solve: the next step's R)
  Vec3List x_end;              // the positions R_end belongs to (empty: none)
  struct Relinearisation {     // world/relinearise.cpp; sized on first use
    std::vector<Mat3> R_start;        // the step's start rotations
    std::vector<TwistModes> modes;    // the linearisation's twist stiffness (empty: none)
    Vec3List v_iter, v_lin, v_best, v_trial, scratch;
    double u_start = 0, k_start = 0;  // J, elastic and kinetic energy at the step's start
    double u_end = 0;                 // J, elastic energy at x_end
    bool u_start_known = false;       // u_start is U(x) (x == the last step's x_end)
  } relin;
  BlockValues A;               // M + h C + h^2 K
  Vec3List f_int, f_ext, b, v_next, x_next;
  Projection projection;
  Vec3List contact_impulse;    // G^T lambda of the last step, N s
  DirectSolver direct;
  PcgSolver pcg;
  LaggedFactor factor;             // MICA with the factored anticipation
  std::vector<Mat3> node_rotation;  // per node, for warping the factor

  // For a world with threads > 1 (empty otherwise): blocks of tets that share no node (parallel
  // assembly) and blocks of nodes that share no block of A (the colour-ordered MBGS sweep).
  Colouring element_colours, node_colours;

  // What A and the factorization were built for; a linear body reuses both while unchanged.
  struct MatrixKey {
    double h = 0, alpha = -1, beta = -1;
    bool operator==(const MatrixKey& o) const { return h == o.h && alpha == o.alpha && beta == o.beta; }
  } matrix_key;
  bool matrix_current = false;   // A holds M + hC + h^2 K for matrix_key
  uint64_t factored_lpc_version = ~uint64_t(0);
  bool factor_current = false;
  bool matrix_rebuilt = false;   // this step assembled A anew

  bool is_dynamic() const { return !settings.is_static; }
  bool has_damping() const { return settings.rayleigh_alpha != 0 || settings.rayleigh_beta != 0; }
};

}  // namespace mica
