// SPDX-License-Identifier: Apache-2.0
// A render mesh embedded in a body's tets: the grid finds the tet a brute-force scan finds; at rest
// and under a rigid motion every bound vertex lands where it should (1e-12 m); vertices outside
// the body are projected within the radius and unbound beyond it, left as they were; the normals
// are the area-weighted normals of the moved triangles; the update allocates nothing; bad input is
// refused by name; arrays at any offset get the same bytes. After a resection the vertices of kept
// tets are placed as before, to the bit, and those of removed tets are bound again; after a cut
// every vertex follows its tet's copies.
#include <cstring>

#include "embedding/embedding.hpp"
#include "embedding/tet_locator.hpp"
// malloc is counted too, except in a sanitizer build: the sanitizer owns malloc (replacing it
// there aborts at start-up), and only operator new is counted.
#if !defined(__SANITIZE_ADDRESS__) && !defined(__SANITIZE_THREAD__)
#define MICA_TEST_COUNT_MALLOC
#endif
#include "haptics/alloc_counter.hpp"
#include "test_util.hpp"
#include "world/topology_change.hpp"

using namespace mica;

namespace {

struct Box {
  TetMesh mesh;
  std::vector<Tri> surface;
};

Box box() {
  Box b;
  b.mesh = make_box_grid(Vec3(-0.05, 0, -0.04), Vec3(0.05, 0.06, 0.04), {5, 3, 4}, 6);
  b.surface = extract_surface(b.mesh);
  return b;
}

// The render mesh of a test: the body's surface nodes and triangles, random points inside, points
// just outside the +x face (2 mm) and far outside (5 cm); their counts.
struct Mesh {
  std::vector<double> xyz;
  std::vector<int32_t> triangles;
  int32_t inside = 0, near = 0, far = 0;
  int32_t count() const { return int32_t(xyz.size() / 3); }
  Vec3 vertex(int32_t i) const { return {xyz[3 * size_t(i)], xyz[3 * size_t(i) + 1], xyz[3 * size_t(i) + 2]}; }
  void add(const Vec3& p) { xyz.insert(xyz.end(), {p.x(), p.y(), p.z()}); }
};

Mesh render_mesh(const Box& b) {
  Mesh m;
  std::vector<int32_t> index(b.mesh.nodes.size(), -1);
  for (const Tri& f : b.surface)
    for (int32_t v : f) {
      if (index[size_t(v)] < 0) {
        index[size_t(v)] = m.count();
        m.add(b.mesh.nodes[size_t(v)]);
      }
      m.triangles.push_back(index[size_t(v)]);
    }
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0.001, 0.999);
  for (int k = 0; k < 500; ++k) m.add(Vec3(-0.05 + 0.1 * u(rng), 0.06 * u(rng), -0.04 + 0.08 * u(rng)));
  m.inside = m.count();
  for (int k = 0; k < 50; ++k) m.add(Vec3(0.052, 0.06 * u(rng), -0.04 + 0.08 * u(rng)));
  m.near = 50;
  for (int k = 0; k < 5; ++k) m.add(Vec3(0.1, 0.06 * u(rng), 0));
  m.far = 5;
  return m;
}

Embedding embed(const Box& b, const Mesh& m, double radius = 0.003) {
  return Embedding(7, b.mesh.nodes, b.mesh.tets, b.surface, m.xyz.data(), m.count(), m.triangles.data(),
                   int32_t(m.triangles.size() / 3), radius);
}

// The normals of `triangles` at xyz, summed per vertex the plain way (Vec3, one triangle at a time).
Vec3List reference_normals(const std::vector<double>& xyz, const std::vector<int32_t>& triangles) {
  Vec3List n(xyz.size() / 3, Vec3::Zero());
  auto p = [&](int32_t v) { return Vec3(xyz[3 * size_t(v)], xyz[3 * size_t(v) + 1], xyz[3 * size_t(v) + 2]); };
  for (size_t t = 0; t < triangles.size(); t += 3) {
    const Vec3 face = (p(triangles[t + 1]) - p(triangles[t])).cross(p(triangles[t + 2]) - p(triangles[t]));
    for (int k = 0; k < 3; ++k) n[size_t(triangles[t + size_t(k)])] += face;
  }
  for (Vec3& v : n)
    if (v.norm() > 0) v.normalize();
  return n;
}

double angle_degrees(const Vec3& a, const Vec3& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b)) * 180 / M_PI;
}

}  // namespace

static void test_grid_finds_the_tet_a_scan_finds(void**) {
  const Box b = box();
  const TetLocator locator(b.mesh.nodes, b.mesh.tets);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-0.06, 0.07);
  int inside = 0;
  for (int k = 0; k < 2000; ++k) {
    const Vec3 p(u(rng), u(rng), u(rng));
    int32_t scan = -1;
    for (size_t e = 0; e < b.mesh.tets.size() && scan < 0; ++e)
      if (locator.weights(int32_t(e), p).minCoeff() >= -1e-9) scan = int32_t(e);
    Weights w;
    const int32_t found = locator.locate(p, 1e-9, w);
    assert_int_equal(found >= 0, scan >= 0);
    if (found < 0) continue;
    ++inside;
    assert_true(w.minCoeff() >= -1e-9);
    assert_near(w.sum(), 1.0, 1e-12);
    Vec3 q = Vec3::Zero();
    for (int a = 0; a < 4; ++a) q += w[a] * b.mesh.nodes[size_t(b.mesh.tets[size_t(found)][size_t(a)])];
    assert_near((q - p).norm(), 0.0, 1e-15);
  }
  assert_true(inside > 400);
}

static void test_rest_places_every_bound_vertex_where_it_was(void**) {
  const Box b = box();
  const Mesh m = render_mesh(b);
  const Embedding e = embed(b, m);
  const std::vector<int32_t>& kinds = e.kinds();
  for (int32_t i = 0; i < m.inside; ++i) assert_int_equal(kinds[size_t(i)], int32_t(VertexKind::Inside));
  for (int32_t i = m.inside; i < m.inside + m.near; ++i) assert_int_equal(kinds[size_t(i)], int32_t(VertexKind::Projected));
  for (int32_t i = m.inside + m.near; i < m.count(); ++i) assert_int_equal(kinds[size_t(i)], int32_t(VertexKind::Unbound));
  assert_int_equal(e.count(VertexKind::Inside), m.inside);
  assert_int_equal(e.count(VertexKind::Projected), m.near);
  assert_int_equal(e.count(VertexKind::Unbound), m.far);

  std::vector<double> out(m.xyz.size(), 42.0);  // unbound vertices keep this
  e.update(b.mesh.nodes, b.mesh.tets, out.data(), nullptr);
  for (int32_t i = 0; i < m.count(); ++i) {
    const Vec3 p(out[3 * size_t(i)], out[3 * size_t(i) + 1], out[3 * size_t(i) + 2]);
    if (kinds[size_t(i)] == int32_t(VertexKind::Unbound))
      assert_true(p == Vec3::Constant(42.0));
    else if ((p - m.vertex(i)).norm() > 1e-12)
      fail_msg("vertex %d (kind %d) is %.3g m from where it was", i, kinds[size_t(i)], (p - m.vertex(i)).norm());
  }
}

static void test_rigid_motion_moves_the_mesh_rigidly(void**) {
  const Box b = box();
  const Mesh m = render_mesh(b);
  const Embedding e = embed(b, m);
  const Mat3 R = Eigen::AngleAxisd(0.7, Vec3(1, 2, -0.5).normalized()).toRotationMatrix();
  const Vec3 t(0.3, -0.2, 0.15);
  Vec3List x = b.mesh.nodes;
  for (Vec3& p : x) p = R * p + t;
  std::vector<double> out = m.xyz, normals(m.xyz.size());
  const Vec3List rest_normals = reference_normals(m.xyz, m.triangles);
  e.update(x, b.mesh.tets, out.data(), normals.data());
  for (int32_t i = 0; i < m.inside + m.near; ++i) {
    const Vec3 p(out[3 * size_t(i)], out[3 * size_t(i) + 1], out[3 * size_t(i) + 2]);
    assert_near((p - (R * m.vertex(i) + t)).norm(), 0.0, 1e-12);
    const Vec3 n(normals[3 * size_t(i)], normals[3 * size_t(i) + 1], normals[3 * size_t(i) + 2]);
    assert_near((n - R * rest_normals[size_t(i)]).norm(), 0.0, 1e-9);
  }
}

static void test_normals_are_those_of_the_moved_triangles(void**) {
  const Box b = box();
  const Mesh m = render_mesh(b);
  const Embedding e = embed(b, m);
  // A bend: not an affine map, so each tet moves its own way.
  Vec3List x = b.mesh.nodes;
  for (Vec3& p : x) p += Vec3(0, 0.3 * p.x() * p.x() + 0.1 * p.z() * p.x(), 0.2 * p.y() * p.x());
  std::vector<double> out = m.xyz, normals(m.xyz.size());
  e.update(x, b.mesh.tets, out.data(), normals.data());
  const Vec3List expected = reference_normals(out, m.triangles);
  const int32_t surface_vertices = int32_t(m.inside - 500);
  for (int32_t i = 0; i < surface_vertices; ++i) {
    const Vec3 n(normals[3 * size_t(i)], normals[3 * size_t(i) + 1], normals[3 * size_t(i) + 2]);
    assert_near(n.norm(), 1.0, 1e-12);
    assert_le(angle_degrees(n, expected[size_t(i)]), 1e-6);
  }
  for (int32_t i = surface_vertices; i < m.count(); ++i)  // in no triangle
    assert_true(Vec3(normals[3 * size_t(i)], normals[3 * size_t(i) + 1], normals[3 * size_t(i) + 2]) == Vec3::Zero());
}

static void test_update_allocates_nothing(void**) {
  const Box b = box();
  const Mesh m = render_mesh(b);
  const Embedding e = embed(b, m);
  std::vector<double> out = m.xyz, normals(m.xyz.size());
  mica_test::start_counting_allocations();
  e.update(b.mesh.nodes, b.mesh.tets, out.data(), normals.data());
  assert_int_equal(mica_test::stop_counting_allocations(), 0);
}

static void test_bad_input_is_refused_by_name(void**) {
  const Box b = box();
  Mesh m = render_mesh(b);
  auto refused = [&](Errc code, const char* phrase, double radius) {
    try {
      embed(b, m, radius);
    } catch (const Error& error) {
      assert_int_equal(int(error.code()), int(code));
      if (!std::strstr(error.what(), phrase)) fail_msg("'%s' does not say '%s'", error.what(), phrase);
      return;
    }
    fail_msg("not refused: %s", phrase);
  };
  m.xyz[3 * 17 + 1] = std::nan("");
  refused(Errc::InvalidArgument, "vertex 17 is not finite (y = nan)", 0.001);
  m.xyz[3 * 17 + 1] = 0.01;
  m.triangles[3 * 4 + 2] = m.count();
  refused(Errc::OutOfRange, "triangle 4 refers to vertex", 0.001);
  m.triangles[3 * 4 + 2] = 0;
  refused(Errc::InvalidArgument, "radius is -1 m", -1);
  refused(Errc::InvalidArgument, "radius is inf m", HUGE_VAL);
}

static void test_update_refuses_another_node_count(void**) {
  const Box b = box();
  const Mesh m = render_mesh(b);
  const Embedding e = embed(b, m);
  Vec3List x = b.mesh.nodes;
  x.pop_back();
  std::vector<double> out(m.xyz.size());
  try {
    e.update(x, b.mesh.tets, out.data(), nullptr);
  } catch (const Error& error) {
    assert_int_equal(int(error.code()), int(Errc::WrongState));
    return;
  }
  fail_msg("a shorter node array was taken");
}


namespace {

// A resection as World::remove_tets makes it: the tets whose centroid has x > cut go, the nodes no
// kept tet holds go, the rest are renumbered in order.
struct Resection {
  TopologyChange change;
  TetMesh mesh;
  std::vector<Tri> surface;
};

Resection resect(const Box& b, double cut) {
  Resection r;
  std::vector<uint8_t> used(b.mesh.nodes.size(), 0);
  std::vector<Tet> kept;
  for (size_t e = 0; e < b.mesh.tets.size(); ++e) {
    Vec3 c = Vec3::Zero();
    for (int32_t i : b.mesh.tets[e]) c += b.mesh.nodes[size_t(i)] / 4;
    if (c.x() > cut) continue;
    kept.push_back(b.mesh.tets[e]);
    r.change.tet_origin.push_back(int32_t(e));
    for (int32_t i : b.mesh.tets[e]) used[size_t(i)] = 1;
  }
  std::vector<int32_t> index(used.size(), -1);
  for (size_t i = 0; i < used.size(); ++i)
    if (used[i]) {
      index[i] = int32_t(r.mesh.nodes.size());
      r.mesh.nodes.push_back(b.mesh.nodes[i]);
      r.change.node_origin.push_back(int32_t(i));
    }
  for (Tet t : kept) {
    for (int32_t& i : t) i = index[size_t(i)];
    r.mesh.tets.push_back(t);
  }
  r.surface = extract_surface(r.mesh);
  r.change.body = 7;
  r.change.topology_version = 1;
  return r;
}

// A bend of the nodes (not affine), so that each vertex's position depends on its own tet.
Vec3List bent(const Vec3List& nodes) {
  Vec3List x = nodes;
  for (Vec3& p : x) p += Vec3(0, 0.3 * p.x() * p.x() + 0.1 * p.z() * p.x(), 0.2 * p.y() * p.x());
  return x;
}

}  // namespace

static void test_resection_keeps_the_vertices_of_kept_tets_and_binds_the_others_again(void**) {
  const Box b = box();
  const Mesh m = render_mesh(b);
  Embedding e = embed(b, m);
  const Vec3List x = bent(b.mesh.nodes);
  std::vector<double> before(m.xyz.size(), 42.0), normals(m.xyz.size());
  e.update(x, b.mesh.tets, before.data(), normals.data());
  std::vector<int32_t> old_tet(size_t(m.count()));
  for (int32_t i = 0; i < m.count(); ++i) old_tet[size_t(i)] = e.tet(i);

  const Resection r = resect(b, 0.01);  // the +x part of the box goes, the near vertices' tets with it
  std::vector<uint8_t> kept(b.mesh.tets.size(), 0);
  for (int32_t o : r.change.tet_origin) kept[size_t(o)] = 1;
  const Embedding::FollowReport report = e.follow(r.change, r.mesh.nodes, r.mesh.tets, r.surface);
  assert_int_equal(e.node_count(), int32_t(r.mesh.nodes.size()));
  assert_true(e.topology_version() == 1);

  Vec3List x_new(r.mesh.nodes.size());  // the same node positions, renumbered
  for (size_t i = 0; i < x_new.size(); ++i) x_new[i] = x[size_t(r.change.node_origin[i])];
  std::vector<double> after(m.xyz.size(), 42.0);
  e.update(x_new, r.mesh.tets, after.data(), normals.data());
  std::vector<double> at_rest(m.xyz.size(), 42.0);
  e.update(r.mesh.nodes, r.mesh.tets, at_rest.data(), nullptr);
  int32_t followed = 0, gone = 0, unbound = 0;
  for (int32_t i = 0; i < m.count(); ++i) {
    const int32_t t = old_tet[size_t(i)];
    const int32_t kind = e.kinds()[size_t(i)];
    if (t >= 0 && kept[size_t(t)]) {  // its tet stays: the same bits
      ++followed;
      assert_int_equal(r.change.tet_origin[size_t(e.tet(i))], t);
      assert_memory_equal(&after[3 * size_t(i)], &before[3 * size_t(i)], 3 * sizeof(double));
      continue;
    }
    if (t < 0) {  // unbound stays unbound, the host's value untouched
      assert_int_equal(kind, int32_t(VertexKind::Unbound));
      assert_true(after[3 * size_t(i)] == 42.0);
      continue;
    }
    ++gone;
    if (kind == int32_t(VertexKind::Unbound)) {
      ++unbound;
      assert_int_equal(e.tet(i), -1);
      assert_true(after[3 * size_t(i)] == 42.0 && at_rest[3 * size_t(i)] == 42.0);
      continue;
    }
    // Bound again, in a kept tet: at rest exactly where it was given.
    assert_true(e.tet(i) >= 0);
    const Vec3 p(at_rest[3 * size_t(i)], at_rest[3 * size_t(i) + 1], at_rest[3 * size_t(i) + 2]);
    assert_near((p - m.vertex(i)).norm(), 0.0, 1e-12);
  }
  print_message("resection: %d vertices followed their tets, %d bound again (%d inside, %d projected, %d unbound)\n",
                followed, gone, report.inside, report.projected, report.unbound);
  assert_int_equal(report.followed, followed);
  assert_int_equal(report.inside + report.projected + report.unbound, gone);
  assert_int_equal(report.unbound, unbound);
  assert_true(gone > 100 && report.inside > 0 && report.projected > 0 && report.unbound > 0);
  // The counts are those of the kinds.
  int32_t counted[3] = {0, 0, 0};
  for (int32_t k : e.kinds()) ++counted[k];
  for (int k = 0; k < 3; ++k) assert_int_equal(e.count(VertexKind(k)), counted[k]);
}

// A cut along the plane x = 0.01 (a plane of the box's nodes) as World::cut makes one: every tet stays, the tets on the +x side
// take copies of the plane's nodes (appended after the old nodes). Moving the +x side's nodes
// (copies included) by d moves exactly the vertices bound on that side.
static void test_cut_vertices_follow_their_tets_copies(void**) {
  const Box b = box();
  const Mesh m = render_mesh(b);
  Embedding e = embed(b, m);
  TopologyChange change;
  change.body = 7;
  change.topology_version = 3;
  TetMesh cut = b.mesh;
  std::vector<int32_t> copy(b.mesh.nodes.size(), -1);
  for (size_t i = 0; i < b.mesh.nodes.size(); ++i) change.node_origin.push_back(int32_t(i));
  std::vector<uint8_t> plus(b.mesh.tets.size(), 0);
  for (size_t t = 0; t < cut.tets.size(); ++t) {
    change.tet_origin.push_back(int32_t(t));
    Vec3 c = Vec3::Zero();
    for (int32_t i : cut.tets[t]) c += b.mesh.nodes[size_t(i)] / 4;
    if (c.x() < 0.01) continue;
    plus[t] = 1;
    for (int32_t& i : cut.tets[t]) {
      if (std::abs(b.mesh.nodes[size_t(i)].x() - 0.01) > 1e-12) continue;
      if (copy[size_t(i)] < 0) {
        copy[size_t(i)] = int32_t(cut.nodes.size());
        cut.nodes.push_back(b.mesh.nodes[size_t(i)]);
        change.node_origin.push_back(i);
      }
      i = copy[size_t(i)];
    }
  }
  assert_true(cut.nodes.size() > b.mesh.nodes.size());
  const std::vector<Tri> surface = extract_surface(cut);
  const int32_t bound = m.count() - e.count(VertexKind::Unbound);
  const Embedding::FollowReport report = e.follow(change, cut.nodes, cut.tets, surface);
  assert_int_equal(report.followed, bound);  // a cut removes no tet: nobody is bound again
  assert_int_equal(report.inside + report.projected + report.unbound, 0);

  const Vec3 d(0.01, -0.02, 0.005);
  std::vector<uint8_t> moved(cut.nodes.size(), 0);
  for (size_t t = 0; t < cut.tets.size(); ++t)
    if (plus[t])
      for (int32_t i : cut.tets[t]) moved[size_t(i)] = 1;
  Vec3List x = cut.nodes;
  for (size_t i = 0; i < x.size(); ++i)
    if (moved[i]) x[i] += d;
  std::vector<double> out(m.xyz.size(), 42.0);
  e.update(x, cut.tets, out.data(), nullptr);
  int32_t on_plus = 0;
  for (int32_t i = 0; i < m.count(); ++i) {
    if (e.tet(i) < 0) continue;
    const Vec3 p(out[3 * size_t(i)], out[3 * size_t(i) + 1], out[3 * size_t(i) + 2]);
    const Vec3 expected = m.vertex(i) + (plus[size_t(e.tet(i))] ? d : Vec3::Zero());
    on_plus += plus[size_t(e.tet(i))];
    if ((p - expected).norm() > 1e-12) fail_msg("vertex %d is %.3g m from where its side put it", i, (p - expected).norm());
  }
  assert_true(on_plus > 50 && on_plus < bound - 50);
}

static void test_a_change_that_does_not_fit_is_refused_and_changes_nothing(void**) {
  const Box b = box();
  const Mesh m = render_mesh(b);
  Embedding e = embed(b, m);
  Resection r = resect(b, 0.01);
  const std::vector<int32_t> kinds = e.kinds();
  r.change.tet_origin[3] = int32_t(b.mesh.tets.size());  // no such tet
  try {
    e.follow(r.change, r.mesh.nodes, r.mesh.tets, r.surface);
    fail_msg("a change naming a tet the embedding never had was followed");
  } catch (const Error& error) {
    assert_int_equal(int(error.code()), int(Errc::InvalidArgument));
    if (!std::strstr(error.what(), "new tet 3 comes from tet")) fail_msg("'%s'", error.what());
  }
  r.change.tet_origin.pop_back();
  try {
    e.follow(r.change, r.mesh.nodes, r.mesh.tets, r.surface);
    fail_msg("a change of another tet count was followed");
  } catch (const Error& error) {
    assert_int_equal(int(error.code()), int(Errc::InvalidArgument));
  }
  assert_true(e.kinds() == kinds);
  assert_int_equal(e.node_count(), int32_t(b.mesh.nodes.size()));
  // What the C layer does when a follow fails: every vertex unbound, the update leaves them be.
  e.unbind_all(int32_t(r.mesh.nodes.size()), int32_t(r.mesh.tets.size()), 5);
  assert_int_equal(e.count(VertexKind::Unbound), m.count());
  std::vector<double> out(m.xyz.size(), 42.0), normals(m.xyz.size());
  e.update(r.mesh.nodes, r.mesh.tets, out.data(), normals.data());
  for (double v : out) assert_true(v == 42.0);
}

// The update's normals come block by block (normals_plan.hpp): in blocks of 16 triangles, with
// triangles that also join the interior, projected and unbound vertices (an unbound corner counts
// where the host put it), they are the moved triangles' normals, and the positions are the bits
// the whole-mesh block gives.
static void test_normals_in_many_blocks_with_every_kind_of_corner(void**) {
  const Box b = box();
  Mesh m = render_mesh(b);
  const int32_t surface_triangles = int32_t(m.triangles.size() / 3);
  for (int32_t k = 0; k < 40; ++k)  // interior, projected and unbound vertices in triangles too
    m.triangles.insert(m.triangles.end(), {m.inside - 1 - k, m.inside + k, m.inside + m.near + k % m.far});
  const int32_t t = int32_t(m.triangles.size() / 3);
  assert_true(t > 4 * 16 && surface_triangles < t);
  const auto embedding = [&](int32_t block) {
    return Embedding(7, b.mesh.nodes, b.mesh.tets, b.surface, m.xyz.data(), m.count(), m.triangles.data(), t,
                     0.003, block);
  };
  const Embedding small = embedding(16), whole = embedding(1 << 20);
  const Vec3List x = bent(b.mesh.nodes);
  std::vector<double> out = m.xyz, normals(m.xyz.size(), 7.0), out_whole = m.xyz, normals_whole(m.xyz.size());
  small.update(x, b.mesh.tets, out.data(), normals.data());
  whole.update(x, b.mesh.tets, out_whole.data(), normals_whole.data());
  assert_memory_equal(out.data(), out_whole.data(), sizeof(double) * out.size());
  const Vec3List expected = reference_normals(out, m.triangles);
  std::vector<uint8_t> used(size_t(m.count()), 0);
  for (int32_t v : m.triangles) used[size_t(v)] = 1;
  for (int32_t i = 0; i < m.count(); ++i) {
    const Vec3 n(&normals[3 * size_t(i)]), n_whole(&normals_whole[3 * size_t(i)]);
    assert_near((n - n_whole).norm(), 0.0, 1e-12);
    if (!used[size_t(i)]) {
      assert_true(n == Vec3::Zero());
      continue;
    }
    assert_near(n.norm(), 1.0, 1e-12);
    assert_le(angle_degrees(n, expected[size_t(i)]), 1e-6);
  }
}

// The host's arrays are written with streaming stores of 16 bytes where they allow it: arrays at
// every offset from a 16-byte boundary (8 is what C guarantees; 4 is what a careless host may pass)
// get the same bytes as aligned ones.
static void test_arrays_at_any_offset_get_the_same_bytes(void**) {
  const Box b = box();
  const Mesh m = render_mesh(b);
  const Embedding e = embed(b, m);
  const Vec3List x = bent(b.mesh.nodes);
  const size_t bytes = sizeof(double) * m.xyz.size();
  std::vector<double> xyz = m.xyz, normals(m.xyz.size());
  e.update(x, b.mesh.tets, xyz.data(), normals.data());
  for (size_t offset : {0, 4, 8, 12}) {
    std::vector<char> at(2 * bytes + 64);
    char* base = at.data() + (16 - reinterpret_cast<uintptr_t>(at.data()) % 16) + offset;
    std::memcpy(base, m.xyz.data(), bytes);  // the unbound vertices' values stay
    e.update(x, b.mesh.tets, reinterpret_cast<double*>(base), reinterpret_cast<double*>(base + bytes));
    assert_memory_equal(base, xyz.data(), bytes);
    assert_memory_equal(base + bytes, normals.data(), bytes);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_grid_finds_the_tet_a_scan_finds),
      cmocka_unit_test(test_rest_places_every_bound_vertex_where_it_was),
      cmocka_unit_test(test_rigid_motion_moves_the_mesh_rigidly),
      cmocka_unit_test(test_arrays_at_any_offset_get_the_same_bytes),
      cmocka_unit_test(test_normals_in_many_blocks_with_every_kind_of_corner),
      cmocka_unit_test(test_normals_are_those_of_the_moved_triangles),
      cmocka_unit_test(test_update_allocates_nothing),
      cmocka_unit_test(test_bad_input_is_refused_by_name),
      cmocka_unit_test(test_update_refuses_another_node_count),
      cmocka_unit_test(test_resection_keeps_the_vertices_of_kept_tets_and_binds_the_others_again),
      cmocka_unit_test(test_cut_vertices_follow_their_tets_copies),
      cmocka_unit_test(test_a_change_that_does_not_fit_is_refused_and_changes_nothing),
  };
  return cmocka_run_group_tests(tests, nullptr, nullptr);
}
