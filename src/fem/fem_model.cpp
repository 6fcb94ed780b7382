// SPDX-License-Identifier: Apache-2.0
#include "fem/fem_model.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "core/error.hpp"
#include "fem/neo_hookean.hpp"
#include "fem/rotation.hpp"

namespace mica {

double FemModel::total_mass() const { return std::accumulate(node_mass.begin(), node_mass.end(), 0.0); }

namespace {
// Throws InvalidArgument naming `where` for a material out of its domain.
void validate_material(const Material& mat, const std::string& where) {
  if (!(mat.youngs_modulus > 0) || !std::isfinite(mat.youngs_modulus))
    fail(Errc::InvalidArgument, where + ": Young's modulus must be finite and > 0 Pa, got " + number_text(mat.youngs_modulus));
  if (!(mat.poisson_ratio >= 0 && mat.poisson_ratio < 0.5))
    fail(Errc::InvalidArgument, where + ": Poisson ratio must be in [0, 0.5), got " + number_text(mat.poisson_ratio));
  if (!(mat.density > 0) || !std::isfinite(mat.density))
    fail(Errc::InvalidArgument, where + ": density must be finite and > 0 kg/m^3, got " + number_text(mat.density));
}

// A tet's mass (kg) and stiffness (E times its size, N/m) must lie within this range and its inverse:
// the step's matrix holds sums of their products with h and h^2, and its factorization squares them,
// so beyond it the system leaves double precision (E = 1e300 Pa, density = 1e-300 kg/m^3). Real
// tissue and tools lie far inside (1e-15 kg to 1e7 kg, 1e-6 N/m to 1e13 N/m).
constexpr double kModelRange = 1e100;

void check_in_range(double value, const char* what, const char* unit, const Material& mat, size_t tet,
                    const std::string& where) {
  if (value >= 1 / kModelRange && value <= kModelRange) return;
  fail(Errc::InvalidArgument, where + ": tet " + std::to_string(tet) + " has a " + what + " of " + number_text(value) +
                                  " " + unit + " (Young's modulus " + number_text(mat.youngs_modulus) +
                                  " Pa, density " + number_text(mat.density) +
                                  " kg/m^3), outside [1e-100, 1e100]: beyond what double precision can solve");
}
}  // namespace

FemModel build_fem_model(const TetMesh& mesh, const Material& material, MassKind mass_kind,
                         const std::string& source) {
  validate_material(material, source);
  return build_fem_model(mesh, std::vector<Material>(mesh.tets.size(), material), mass_kind, source);
}

FemModel build_fem_model(const TetMesh& mesh, const std::vector<Material>& materials, MassKind mass_kind,
                         const std::string& source) {
  if (materials.size() != mesh.tets.size())
    fail(Errc::InvalidArgument, source + ": " + std::to_string(materials.size()) + " materials for " +
                                    std::to_string(mesh.tets.size()) + " tets (one per tet)");
  for (size_t e = 0; e < materials.size(); ++e) validate_material(materials[e], source + ": tet " + std::to_string(e));
  validate_topology(mesh, source);
  FemModel m;
  m.quality = check_rest_quality(mesh, source);
  m.rest = mesh.nodes;
  m.materials = materials;
  m.lame.reserve(materials.size());
  for (const Material& mat : materials) m.lame.push_back(lame_parameters(mat));
  m.mass_kind = mass_kind;
  m.elements.reserve(mesh.tets.size());
  for (size_t e = 0; e < mesh.tets.size(); ++e) {
    m.elements.push_back(make_tet_element(m.rest, mesh.tets[e]));
    // The quality check is scale-free; double precision is not: a tet of edge 1e-104 m has a
    // subnormal determinant (its inverse overflows) and one of 1e102 m overflows its mass.
    const TetElement& el = m.elements.back();
    if (!el.dm_inv.allFinite() || !std::isfinite(materials[e].density * el.volume) ||
        !std::isfinite(materials[e].youngs_modulus * el.volume))
      fail(Errc::BadMesh, source + ": tet " + std::to_string(e) + " (volume " + number_text(el.volume) +
                              " m^3) is too small or too large to model in double precision");
    check_in_range(materials[e].density * el.volume, "mass", "kg", materials[e], e, source);
    check_in_range(materials[e].youngs_modulus * std::cbrt(el.volume), "stiffness", "N/m", materials[e], e, source);
  }
  m.pattern = build_block_pattern(m.node_count(), mesh.tets);
  m.node_element_start.assign(size_t(m.node_count()) + 1, 0);
  for (const Tet& t : mesh.tets)
    for (int32_t a : t) ++m.node_element_start[size_t(a) + 1];
  for (size_t i = 0; i + 1 < m.node_element_start.size(); ++i) m.node_element_start[i + 1] += m.node_element_start[i];
  m.node_elements.resize(size_t(m.node_element_start.back()));
  std::vector<int32_t> next(m.node_element_start.begin(), m.node_element_start.end() - 1);
  for (size_t e = 0; e < mesh.tets.size(); ++e)
    for (int32_t a : mesh.tets[e]) m.node_elements[size_t(next[size_t(a)]++)] = int32_t(e);
  m.slots = element_block_slots(m.pattern, mesh.tets);

  // Consistent: M_ab = rho V / 20 (1 + delta_ab); lumped: rho V / 4 on the diagonal.
  m.mass.assign(m.pattern.block_count(), 0.0);
  for (size_t e = 0; e < m.elements.size(); ++e) {
    const double rv = materials[e].density * m.elements[e].volume;
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b) {
        const int32_t slot = m.slots[e][4 * a + b];
        if (mass_kind == MassKind::Lumped)
          m.mass[slot] += (a == b) ? rv / 4 : 0.0;
        else
          m.mass[slot] += (a == b) ? rv / 10 : rv / 20;
      }
  }
  m.node_mass.assign(size_t(m.node_count()), 0.0);
  for (int32_t i = 0; i < m.pattern.rows; ++i)
    for (int32_t k = m.pattern.row_start[i]; k < m.pattern.row_start[i + 1]; ++k) m.node_mass[i] += m.mass[k];
  // Each tet in range is not enough: the sums (node masses, the body's mass, gravity's m g)
  // must be too.
  if (!std::isfinite(m.total_mass() * 1e3))
    fail(Errc::BadMesh, source + ": the body's mass overflows double precision (it is too large to model)");
  return m;
}

void compute_rotations(const FemModel& m, const Vec3List& x, std::vector<Mat3>& R, ThreadPool* pool) {
  parallel_for(pool, int64_t(m.elements.size()), 64, [&](int32_t first, int32_t last) {
    const auto F = [&](int32_t e) { return deformation_gradient(m.elements[e], x); };
    int32_t e = first;
    for (; e + 4 <= last; e += 4) {  // four at a time, for proper_rotations4
      const Mat3 F4[4] = {F(e), F(e + 1), F(e + 2), F(e + 3)};  // made in place (a copy would stall)
      proper_rotations4(F4, &R[e]);
    }
    Mat3 tail[3];
    for (int32_t j = 0; e + j < last; ++j) tail[j] = F(e + j);
    proper_rotations(tail, R.data() + e, last - e);
  });
}

void compute_node_rotations(const FemModel& m, const std::vector<Mat3>& element_rotation,
                            std::vector<Mat3>& node_rotation) {
  const size_t n = size_t(m.node_count());
  node_rotation.resize(n);
  for (size_t i = 0; i < n; i += 4) {  // four at a time, for proper_rotations4
    const int count = int(std::min<size_t>(4, n - i));
    // Each sum S of the node's element rotations (gathered, in element order) scaled to
    // |S|_F^2 = 3, as a rotation's (its polar factor is the same): det S is then near 1, where
    // Newton's scaling needs no cube root.
    Mat3 S[4];
    for (int j = 0; j < count; ++j) {
      Mat3 sum = Mat3::Zero();
      for (int32_t k = m.node_element_start[i + j]; k < m.node_element_start[i + j + 1]; ++k)
        sum += element_rotation[size_t(m.node_elements[size_t(k)])];
      const double n2 = sum.squaredNorm();
      S[j] = n2 > 0 ? Mat3(sum * std::sqrt(3 / n2)) : sum;
    }
    proper_rotations(S, &node_rotation[i], count);
    for (int j = 0; j < count; ++j)
      if (S[j].isZero(0)) node_rotation[i + j].setIdentity();  // a node in no element
  }
}

void assemble_elastic(const FemModel& m, const Vec3List& x, const std::vector<Mat3>* R, double k_scale,
                      BlockValues* K, Vec3List& f_int, const Colouring* element_colours, ThreadPool* pool) {
  const bool coloured = pool && element_colours && !element_colours->empty();
  parallel_for(coloured ? pool : nullptr, int64_t(f_int.size()), 4096, [&](int32_t first, int32_t last) {
    for (int32_t i = first; i < last; ++i) f_int[i].setZero();
  });
  const Mat3 I = Mat3::Identity();
  Mat3* blocks = K ? K->data() : nullptr;
  // Elements first to last, four at a time (add_elements4), then a pair (add_elements), then one.
  auto elements = [&](int32_t first, int32_t last) {
    int32_t e = first;
    for (; e + 3 < last; e += 4) {
      const TetElement* el[4] = {&m.elements[e], &m.elements[e + 1], &m.elements[e + 2], &m.elements[e + 3]};
      const Lame* lame[4] = {&m.lame[e], &m.lame[e + 1], &m.lame[e + 2], &m.lame[e + 3]};
      const Mat3* rot[4];
      for (int l = 0; l < 4; ++l) rot[l] = R ? &(*R)[e + l] : &I;
      const std::array<int32_t, 16>* slots[4] = {&m.slots[e], &m.slots[e + 1], &m.slots[e + 2], &m.slots[e + 3]};
      add_elements4(el, lame, rot, x, k_scale, slots, blocks, f_int);
    }
    if (e + 1 < last) {
      const TetElement* el[2] = {&m.elements[e], &m.elements[e + 1]};
      const Lame* lame[2] = {&m.lame[e], &m.lame[e + 1]};
      const Mat3* rot[2] = {R ? &(*R)[e] : &I, R ? &(*R)[e + 1] : &I};
      const std::array<int32_t, 16>* slots[2] = {&m.slots[e], &m.slots[e + 1]};
      add_elements(el, lame, rot, x, k_scale, slots, blocks, f_int);
      e += 2;
    }
    if (e < last) add_element(m.elements[e], m.lame[e], R ? (*R)[e] : I, x, k_scale, m.slots[e], blocks, f_int);
  };
  if (!coloured) {
    elements(0, int32_t(m.elements.size()));
    return;
  }
  const Colouring& c = *element_colours;
  auto colour_blocks = [&](int32_t, int32_t first, int32_t last, int32_t) {
    for (int32_t n = first; n < last; ++n) elements(c.block_start[c.order[n]], c.block_start[c.order[n] + 1]);
  };
  pool->phased_for(c.start.data(), c.colours(), 1, colour_blocks);
}

void set_scaled_mass(const FemModel& m, double scale, BlockValues& A, ThreadPool* pool) {
  parallel_for(pool, int64_t(A.size()), 4096, [&](int32_t first, int32_t last) {
    for (int32_t k = first; k < last; ++k) A[k] = (scale * m.mass[k]) * Mat3::Identity();
  });
}

void add_scaled_mass(const FemModel& m, double scale, BlockValues& A) {
  for (size_t k = 0; k < A.size(); ++k) A[k].diagonal().array() += scale * m.mass[k];
}

void mass_multiply(const FemModel& m, const Vec3List& v, Vec3List& out) {
  const BlockPattern& p = m.pattern;
  for (int32_t i = 0; i < p.rows; ++i) {
    Vec3 sum = Vec3::Zero();
    for (int32_t k = p.row_start[i]; k < p.row_start[i + 1]; ++k) sum += m.mass[k] * v[p.col[k]];
    out[i] = sum;
  }
}

double mass_dot(const FemModel& m, const Vec3List& v, const Vec3List& w) {
  const BlockPattern& p = m.pattern;
  double s = 0;
  for (int32_t i = 0; i < p.rows; ++i) {
    Vec3 sum = Vec3::Zero();
    for (int32_t k = p.row_start[i]; k < p.row_start[i + 1]; ++k) sum += m.mass[k] * w[p.col[k]];
    s += v[i].dot(sum);
  }
  return s;
}

double elastic_energy(const FemModel& m, const Vec3List& x, bool corotational) {
  double energy = 0;
  for (size_t e = 0; e < m.elements.size(); ++e) {
    const TetElement& el = m.elements[e];
    const Mat3 F = deformation_gradient(el, x);
    energy += elastic_energy(el, m.lame[e], corotational ? proper_rotation(F) : Mat3::Identity(), F);
  }
  return energy;
}

double elastic_energy(const FemModel& m, const Vec3List& x, ElasticModel model) {
  if (model == ElasticModel::NeoHookean) return neo_hookean_energy(m, x);
  return elastic_energy(m, x, model == ElasticModel::Corotational);
}

double kinetic_energy(const FemModel& m, const Vec3List& v) {
  Vec3List Mv(v.size());
  mass_multiply(m, v, Mv);
  return 0.5 * flat(v).dot(flat(Mv));
}

}  // namespace mica
