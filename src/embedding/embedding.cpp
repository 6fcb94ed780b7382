// SPDX-License-Identifier: Apache-2.0
#include "embedding/embedding.hpp"

#include <cmath>
#include <memory>
#include <string>

#include "core/error.hpp"
#include "embedding/surface_projection.hpp"
#include "embedding/tet_locator.hpp"
#include "embedding/vertex_normals.hpp"

namespace mica {

namespace {

// A vertex on a tet's face (or the body's surface) has weights of -1e-16 or so from round-off: it
// counts as inside.
constexpr double kInsideTolerance = 1e-9;

void check_input(const double* xyz, int32_t vertex_count, const int32_t* triangles, int32_t triangle_count,
                 double radius) {
  if (!std::isfinite(radius) || radius < 0)
    fail(Errc::InvalidArgument, "radius is " + number_text(radius) + " m, must be finite and >= 0");
  for (int32_t i = 0; i < vertex_count; ++i)
    for (int a = 0; a < 3; ++a)
      if (!std::isfinite(xyz[3 * size_t(i) + size_t(a)]))
        fail(Errc::InvalidArgument, "vertex " + std::to_string(i) + " is not finite (" + "xyz"[a] + " = " +
                                        number_text(xyz[3 * size_t(i) + size_t(a)]) + ")");
  for (int32_t t = 0; t < triangle_count; ++t)
    for (int k = 0; k < 3; ++k) {
      const int32_t v = triangles[3 * size_t(t) + size_t(k)];
      if (v < 0 || v >= vertex_count)
        fail(Errc::OutOfRange, "triangle " + std::to_string(t) + " refers to vertex " + std::to_string(v) +
                                   ", outside 0.." + std::to_string(vertex_count - 1));
    }
}

}  // namespace

Embedding::Embedding(uint64_t body, const Vec3List& rest, const std::vector<Tet>& tets,
                     const std::vector<Tri>& surface, const double* xyz, int32_t vertex_count,
                     const int32_t* triangles, int32_t triangle_count, double radius)
    : body_(body), node_count_(int32_t(rest.size())) {
  check_input(xyz, vertex_count, triangles, triangle_count, radius);
  const TetLocator locator(rest, tets);
  std::unique_ptr<SurfaceProjection> projection;  // made for the first vertex outside the body
  bindings_.resize(size_t(vertex_count));
  kinds_.resize(size_t(vertex_count));
  for (int32_t i = 0; i < vertex_count; ++i) {
    const Vec3 p(xyz[3 * size_t(i)], xyz[3 * size_t(i) + 1], xyz[3 * size_t(i) + 2]);
    Weights w;
    VertexKind kind = VertexKind::Inside;
    int32_t e = locator.locate(p, kInsideTolerance, w);
    if (e < 0) {
      if (!projection) projection = std::make_unique<SurfaceProjection>(rest, tets, surface);
      double distance;
      e = projection->nearest_tet(p, radius, distance);
      kind = e < 0 ? VertexKind::Unbound : VertexKind::Projected;
      if (e >= 0) w = locator.weights(e, p);
    }
    Binding& b = bindings_[size_t(i)];
    if (e < 0) {
      b.nodes = {-1, -1, -1, -1};
      b.weights = {0, 0, 0, 0};
    } else {
      b.nodes = tets[size_t(e)];
      b.weights = {w[0], w[1], w[2], w[3]};
    }
    kinds_[size_t(i)] = int32_t(kind);
    ++counts_[size_t(kind)];
  }
  triangles_.assign(triangles, triangles + 3 * size_t(triangle_count));
}

void Embedding::update(const Vec3List& x, double* out_xyz, double* out_normals) const {
  if (int32_t(x.size()) != node_count_)
    fail(Errc::WrongState, "the body has " + std::to_string(x.size()) + " nodes, " + std::to_string(node_count_) +
                               " when the embedding was made");
  const size_t n = bindings_.size();
  for (size_t i = 0; i < n; ++i) {
    const Binding& b = bindings_[i];
    if (b.nodes[0] < 0) continue;  // unbound: the host's value stays
    const double *x0 = x[size_t(b.nodes[0])].data(), *x1 = x[size_t(b.nodes[1])].data(),
                 *x2 = x[size_t(b.nodes[2])].data(), *x3 = x[size_t(b.nodes[3])].data();
    const double w0 = b.weights[0], w1 = b.weights[1], w2 = b.weights[2], w3 = b.weights[3];
    double* out = out_xyz + 3 * i;
    for (int a = 0; a < 3; ++a) out[a] = w0 * x0[a] + w1 * x1[a] + w2 * x2[a] + w3 * x3[a];
  }
  if (out_normals) vertex_normals(out_xyz, vertex_count(), triangles_.data(), triangle_count(), out_normals);
}

}  // namespace mica
