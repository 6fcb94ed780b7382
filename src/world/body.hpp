// SPDX-License-Identifier: Apache-2.0
// A deformable (or static) body in three parts: the model it was made with (changed only by
// World::set_body_materials, and by World::remove_tets, which rebuilds the whole body), the state
// a step starts from and leaves, and the step's work arrays, sized once at creation so that
// stepping does not allocate. A step writes only into the work arrays until it
// commits (World::commit swaps what it made into the state), so a step that fails leaves the state
// as it was. Body is the three together.
#pragma once
#include <string>
#include <vector>

#include "collision/bvh.hpp"
#include "collision/pseudo_normals.hpp"
#include "core/colouring.hpp"
#include "fem/fem_model.hpp"
#include "fem/neo_hookean.hpp"
#include "fem/rotation_stiffness.hpp"
#include "solver/projection.hpp"
#include "solver/velocity_solver.hpp"

namespace mica {

constexpr double kDefaultCuttingResistance = 200;  // N/m: of the order of soft tissue's toughness, J/m^2

struct BodySettings {
  Material material;
  double rayleigh_alpha = 0;  // 1/s
  double rayleigh_beta = 0;   // s
  MassKind mass = MassKind::Consistent;
  ElasticModel model = ElasticModel::Corotational;
  bool corotational() const { return model == ElasticModel::Corotational; }
  bool neo_hookean() const { return model == ElasticModel::NeoHookean; }
  bool is_static = false;
};

// What the body was made with.
struct BodyModel {
  BodyModel(const TetMesh& mesh, const BodySettings& settings, const std::string& name, uint64_t key);
  // With a material per tet (a body whose tets changed keeps each one's).
  BodyModel(const TetMesh& mesh, const std::vector<Material>& materials, const BodySettings& settings,
            const std::string& name, uint64_t key);

  BodySettings settings;
  std::string name;            // "body 0x..." in messages
  uint64_t key;                // unique in its world, never reused: the solver's caches are keyed by it
  FemModel fem;                // rebuilt by World::set_body_materials (same rest shape and tets)
  std::vector<Tet> tets;
  std::vector<int32_t> regions;  // per tet: the mesh file's region (Gmsh physical tag), else 0
  std::vector<double> cutting_resistance;  // per tet, N/m of blade edge (World::set_cutting_resistance)
  std::vector<Tri> surface;
  std::vector<int32_t> surface_node_list;  // candidates for contact
  double surface_edge = 0;                 // m, mean surface edge length: the deepest penetration looked for
  SurfacePseudoNormals pseudo_normals;     // the surface's edges and corners: its pseudo-normals at x, when asked
  // For a world with threads > 1 (empty otherwise): blocks of tets that share no node (parallel
  // assembly) and blocks of nodes that share no block of A (the colour-ordered MBGS sweep).
  Colouring element_colours, node_colours;

  bool is_dynamic() const { return !settings.is_static; }
  bool has_damping() const { return settings.rayleigh_alpha != 0 || settings.rayleigh_beta != 0; }

 private:
  BodyModel(const TetMesh& mesh, FemModel&& model, const BodySettings& settings, const std::string& name,
            uint64_t key);
};

// What a step starts from and leaves.
struct BodyState {
  explicit BodyState(const BodyModel& model);

  Vec3List x, v;
  Vec3List v_previous;          // v at the last step's start (v itself when the host set v): the warm start's trend
  Vec3List node_forces;        // persistent user loads, N
  bool has_node_forces = false;
  uint64_t lpc_version = 0;    // bumped when a constraint on this body is added or removed
  uint64_t topology_version = 0;  // bumped by each change of the tets (World::remove_tets)
  TriangleBvh bvh;             // over the surface triangles at x, refit every step
  // Co-rotational bodies: what the last step found at its end positions, the next step's start
  // rotations (World::start_rotations reuses them while x is still end.x).
  struct EndRotations {
    Vec3List x;                 // the positions (empty: none)
    std::vector<Mat3> R;        // each element's rotation at x
    double u = 0;               // J, the elastic energy at x
  } end;
};

// The step's work arrays (and the cache of a linear body's A, kept while its system stays).
struct BodyScratch {
  explicit BodyScratch(const BodyModel& model);

  // The element rotations the step is (the last step was) linearised with, Body::rotations(): the
  // state's end.R when the step starts where the last one ended (read in place, not copied; after
  // the commit's swap they are next_end.R), else own_R.
  enum class RotationsIn : uint8_t { Own, End, NextEnd } rotations_in = RotationsIn::Own;
  std::vector<Mat3> own_R;
  BodyState::EndRotations next_end;  // this step's end rotations: end once the step commits
  struct Relinearisation {     // world/relinearise.cpp; sized on first use
    std::vector<Mat3> R_start;        // the step's start rotations
    std::vector<TwistModes> modes;    // the linearisation's twist stiffness (empty: none)
    Vec3List v_iter, v_lin, v_best, v_trial, scratch;
    Vec3List x_lin;                   // neo-Hookean: x + h v_lin, where the step is linearised
    double round_off = 0;             // J, neo-Hookean: the model error's floor (relinearise.cpp)
    double u_start = 0, k_start = 0;  // J, elastic and kinetic energy at the step's start
    bool u_start_known = false;       // u_start is U(x) (x == the last step's end.x)
  } relin;
  // Neo-Hookean bodies: the per-element quadratic model the step's system was assembled from (the
  // re-linearisation's check reads it back).
  NeoHookeanLinearisation neo_hookean;
  BlockValues A;               // M + h C + h^2 K
  Vec3List f_int, f_ext, b, v_next, x_next;
  Vec3List contact_impulse;    // G^T lambda of the step, N s
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
  int32_t step_index = -1;       // among the step's dynamic bodies (Contact::a.body); -1: static
  uint64_t matrix_version = 0;   // bumped whenever the values of A change (the solvers' factors follow it)
};

struct Body : BodyModel, BodyState, BodyScratch {
  Body(const TetMesh& mesh, const BodySettings& settings, const std::string& name, uint64_t key);
  Body(const TetMesh& mesh, const std::vector<Material>& materials, const BodySettings& settings,
       const std::string& name, uint64_t key);
  const BodyModel& model() const { return *this; }
  const std::vector<Mat3>& rotations() const {
    return rotations_in == RotationsIn::End ? end.R : rotations_in == RotationsIn::NextEnd ? next_end.R : own_R;
  }
};

}  // namespace mica
