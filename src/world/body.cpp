#include "world/body.hpp"

namespace mica {

Body::Body(const TetMesh& mesh, const BodySettings& s, const std::string& body_name)
    : settings(s), name(body_name), fem(build_fem_model(mesh, s.material, s.mass, body_name)),
      tets(mesh.tets), surface(extract_surface(mesh)),
      surface_node_list(surface_nodes(surface)) {
  const size_t n = fem.rest.size();
  x = fem.rest;
  v.assign(n, Vec3::Zero());
  node_forces.assign(n, Vec3::Zero());
  R.assign(fem.elements.size(), Mat3::Identity());
  R_end.assign(fem.elements.size(), Mat3::Identity());
  A.assign(fem.pattern.block_count(), Mat3::Zero());
  for (Vec3List* w : {&f_int, &f_ext, &b, &v_next, &x_next, &contact_impulse}) w->assign(n, Vec3::Zero());
  projection.reset(int32_t(n));
  pcg.reserve(n);
  bvh.build(x, surface);
  pseudo_normals.build(surface, n);
  pseudo_normals.update(x, surface);
  for (const Tri& t : surface)
    for (int k = 0; k < 3; ++k) surface_edge += (x[t[k]] - x[t[(k + 1) % 3]]).norm();
  surface_edge /= double(3 * surface.size());
}

}  // namespace mica
