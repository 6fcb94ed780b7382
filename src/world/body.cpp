// SPDX-License-Identifier: Apache-2.0
#include "world/body.hpp"

namespace mica {

BodyModel::BodyModel(const TetMesh& mesh, const BodySettings& s, const std::string& body_name, uint64_t body_key)
    : BodyModel(mesh, build_fem_model(mesh, s.material, s.mass, body_name), s, body_name, body_key) {}

BodyModel::BodyModel(const TetMesh& mesh, const std::vector<Material>& materials, const BodySettings& s,
                     const std::string& body_name, uint64_t body_key)
    : BodyModel(mesh, build_fem_model(mesh, materials, s.mass, body_name), s, body_name, body_key) {}

BodyModel::BodyModel(const TetMesh& mesh, FemModel&& model, const BodySettings& s, const std::string& body_name,
                     uint64_t body_key)
    : settings(s), name(body_name), key(body_key), fem(std::move(model)),
      tets(mesh.tets), regions(mesh.regions.empty() ? std::vector<int32_t>(mesh.tets.size(), 0) : mesh.regions),
      cutting_resistance(mesh.tets.size(), kDefaultCuttingResistance),
      surface(extract_surface(mesh)),
      surface_node_list(surface_nodes(surface)) {
  const Vec3List& x = fem.rest;
  for (const Tri& t : surface)
    for (int k = 0; k < 3; ++k) surface_edge += (x[t[k]] - x[t[(k + 1) % 3]]).norm();
  surface_edge /= double(3 * surface.size());
  pseudo_normals.build(surface, x.size());
}

BodyState::BodyState(const BodyModel& model) {
  const size_t n = model.fem.rest.size();
  x = model.fem.rest;
  v.assign(n, Vec3::Zero());
  v_previous.assign(n, Vec3::Zero());
  node_forces.assign(n, Vec3::Zero());
  end.R.assign(model.fem.elements.size(), Mat3::Identity());  // sized once: the step swaps it with next_end.R
  bvh.build(x, model.surface);
}

BodyScratch::BodyScratch(const BodyModel& model) {
  const size_t n = model.fem.rest.size();
  own_R.assign(model.fem.elements.size(), Mat3::Identity());
  if (model.settings.neo_hookean()) {
    neo_hookean.resize(model.fem.elements.size());
    relin.x_lin.resize(n);
    relin.v_lin.resize(n);
  }
  next_end.R.assign(model.fem.elements.size(), Mat3::Identity());
  A.assign(model.fem.pattern.block_count(), Mat3::Zero());
  for (Vec3List* w : {&f_int, &f_ext, &b, &v_next, &x_next, &contact_impulse}) w->assign(n, Vec3::Zero());
  projection.reset(int32_t(n));
  constrained_sum.assign(n, Mat3::Zero());
}

Body::Body(const TetMesh& mesh, const BodySettings& settings, const std::string& name, uint64_t key)
    : BodyModel(mesh, settings, name, key), BodyState(model()), BodyScratch(model()) {}

Body::Body(const TetMesh& mesh, const std::vector<Material>& materials, const BodySettings& settings,
           const std::string& name, uint64_t key)
    : BodyModel(mesh, materials, settings, name, key), BodyState(model()), BodyScratch(model()) {}

}  // namespace mica
