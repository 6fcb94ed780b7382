// SPDX-License-Identifier: Apache-2.0
// A deformable (or static) body in three parts: the model it was made with (never changed after
// creation), the state a step starts from and leaves, and the per-step work arrays, sized once at
// creation so that stepping does not allocate. Body is the three together; a function that needs
// one part takes that part.
#pragma once
#include <string>
#include <vector>

#include "collision/bvh.hpp"
#include "collision/pseudo_normals.hpp"
#include "core/colouring.hpp"
#include "fem/fem_model.hpp"
#include "fem/rotation_stiffness.hpp"
#include "solver/projection.hpp"
#include "solver/velocity_solver.hpp"

namespace mica {

struct BodySettings {
  Material material;
  double rayleigh_alpha = 0;  // 1/s
  double rayleigh_beta = 0;   // s
  MassKind mass = MassKind::Consistent;
  bool corotational = true;
  bool is_static = false;
};

// What the body was made with.
struct BodyModel {
  BodyModel(const TetMesh& mesh, const BodySettings& settings, const std::string& name, uint64_t key);

  BodySettings settings;
  std::string name;            // "body 0x..." in messages
  uint64_t key;                // unique in its world, never reused: the solver's caches are keyed by it
  FemModel fem;                // rebuilt by World::set_body_materials (same rest shape and tets)
  std::vector<Tet> tets;
  std::vector<int32_t> regions;  // per tet: the mesh file's region (Gmsh physical tag), else 0
  std::vector<Tri> surface;
  std::vector<int32_t> surface_node_list;  // candidates for contact
  double surface_edge = 0;                 // m, mean surface edge length: the deepest penetration looked for
  SurfacePseudoNormals pseudo_normals;     // the surface's edges and corners: its pseudo-normals at x, when asked
  // For a world with threads > 1 (empty otherwise): blocks of tets that share no node (parallel
  // assembly) and blocks of nodes that share no block of A (the colour-ordered MBGS sweep).
  Colouring element_colours, node_colours;

  bool is_dynamic() const { return !settings.is_static; }
  bool has_damping() const { return settings.rayleigh_alpha != 0 || settings.rayleigh_beta != 0; }
};

// What a step starts from and leaves.
struct BodyState {
  explicit BodyState(const BodyModel& model);

  Vec3List x, v;
  Vec3List v_previous;          // v at the last step's start (v itself when the host set v): the warm start's trend
  Vec3List node_forces;        // persistent user loads, N
  bool has_node_forces = false;
  uint64_t lpc_version = 0;    // bumped when a constraint on this body is added or removed
  Vec3List contact_impulse;    // G^T lambda of the last step, N s
  TriangleBvh bvh;                         // over the surface triangles at x, refit every step
};

// The step's work arrays (and what one step hands the next: R_end at x_end, A of a linear body).
struct BodyScratch {
  explicit BodyScratch(const BodyModel& model);

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
  std::vector<Mat3> constrained_sum;  // per node, sum of I - S over its constraint groups (reactions)
  Projection projection;
  // The contact-curvature terms this step put into A (World::add_contact_stiffness): their
  // h^2 F K_c over the triangle's corners (what the solver sees), and per term the contact's index
  // and the point of the tool's core the contact force passes through (its line of action).
  // compute_forces hands their impulse to the tool. Cleared each step, they keep their capacity.
  struct CurvatureTerm {
    int32_t contact;
    Vec3 core_point;
  };
  std::vector<TriangleStiffness> curvature_stiffness;
  std::vector<CurvatureTerm> curvature_terms;  // curvature_stiffness[k]'s contact and core point

  // What A was built for; a linear body reuses it while unchanged.
  SystemKey matrix_key{0, -1, -1};
  bool matrix_current = false;   // A holds M + hC + h^2 K for matrix_key
  bool matrix_rebuilt = false;   // this step assembled A anew
  uint64_t matrix_version = 0;   // bumped whenever the values of A change (the solvers' factors follow it)
};

struct Body : BodyModel, BodyState, BodyScratch {
  Body(const TetMesh& mesh, const BodySettings& settings, const std::string& name, uint64_t key);
  const BodyModel& model() const { return *this; }
  const BodyState& state() const { return *this; }
};

}  // namespace mica
