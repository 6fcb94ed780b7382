// SPDX-License-Identifier: Apache-2.0
// The finite-element model of one body: what is constant (rest shape, elements, mass,
// matrix pattern) and the routines that assemble A = M + h C + h^2 K and the forces from it.
#pragma once
#include <string>
#include <vector>

#include "core/colouring.hpp"
#include "core/thread_pool.hpp"
#include "core/types.hpp"
#include "fem/block_matrix.hpp"
#include "fem/material.hpp"
#include "fem/tet_element.hpp"
#include "mesh/tet_mesh.hpp"

namespace mica {

enum class MassKind { Consistent, Lumped };

struct FemModel {
  Vec3List rest;
  std::vector<TetElement> elements;
  std::vector<Material> materials;             // per element (tissue regions)
  std::vector<Lame> lame;                      // per element, from materials
  MassKind mass_kind;
  BlockPattern pattern;
  std::vector<std::array<int32_t, 16>> slots;  // per element, block index of (a, b)
  std::vector<double> mass;                    // scalar mass per block (M_ij = mass * I)
  std::vector<double> node_mass;               // row sums of M: the node's share, kg
  // Per node, the elements that hold it in ascending order: node i's are node_elements[
  // node_element_start[i] .. node_element_start[i + 1]).
  std::vector<int32_t> node_element_start, node_elements;
  QualityReport quality;                       // rest-shape quality: slivers are kept but reported

  int32_t node_count() const { return int32_t(rest.size()); }
  double total_mass() const;
};

// Validates the mesh (topology, rest quality) and the materials, and precomputes the model.
// Throws Error naming the offending element; `source` prefixes messages.
FemModel build_fem_model(const TetMesh& mesh, const Material& material, MassKind mass_kind,
                         const std::string& source);
// One material per tet (`materials.size()` == the tet count): stiffness, mass and so Rayleigh
// damping (alpha M + beta K) are per element.
FemModel build_fem_model(const TetMesh& mesh, const std::vector<Material>& materials, MassKind mass_kind,
                         const std::string& source);

// Per-element rotations of the current positions x, on the threads of `pool` if there is one
// (each element's own: the result does not depend on the pool).
void compute_rotations(const FemModel& m, const Vec3List& x, std::vector<Mat3>& R, ThreadPool* pool = nullptr);

// Per node, the rotation nearest the sum of its elements' rotations (identity for a node in no
// element).
void compute_node_rotations(const FemModel& m, const std::vector<Mat3>& element_rotation,
                            std::vector<Mat3>& node_rotation);

// f_int = sum of element elastic forces at x; when K is not null also K += k_scale * sum R Ke R^T.
// R == nullptr means the linear model (R = I for every element). Serial in element order, or,
// with a pool and a colouring of the elements (blocks of a colour share no node), colour by
// colour on the pool's threads: every block of A and every force has one writer at a time and
// no per-step buffer is needed; the sums then run in colour order rather than element order, so
// A and f_int differ from the serial ones by round-off (but not with the thread count: the
// order is the colouring's).
void assemble_elastic(const FemModel& m, const Vec3List& x, const std::vector<Mat3>* R, double k_scale,
                      BlockValues* K, Vec3List& f_int, const Colouring* element_colours = nullptr,
                      ThreadPool* pool = nullptr);

// A = scale * M (overwrites every block, so it also clears A).
void set_scaled_mass(const FemModel& m, double scale, BlockValues& A, ThreadPool* pool = nullptr);
// A += scale * M
void add_scaled_mass(const FemModel& m, double scale, BlockValues& A);
// out = M v
void mass_multiply(const FemModel& m, const Vec3List& v, Vec3List& out);
// v^T M w
double mass_dot(const FemModel& m, const Vec3List& v, const Vec3List& w);

// Strain energy at x; co-rotational uses each element's own rotation of x, linear R = I.
double elastic_energy(const FemModel& m, const Vec3List& x, bool corotational);
// Strain energy at x of the given model (neo-Hookean: fem/neo_hookean.hpp).
double elastic_energy(const FemModel& m, const Vec3List& x, ElasticModel model);
double kinetic_energy(const FemModel& m, const Vec3List& v);

}  // namespace mica
