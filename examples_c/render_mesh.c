/* SPDX-License-Identifier: Apache-2.0 */
/* A fine render mesh driven by a coarse simulation mesh: the 10 cm cube of sphere_indent, meshed
 * as 6 x 6 x 6 cells of 5 tets, wears a surface 16 times finer (each surface edge cut in four,
 * each triangle into 16: scenes/fine_surface.h) while a 2 cm sphere presses 15 mm into its top and
 * holds.
 *
 * The fine mesh is bound once (mica_embedding_create: each vertex to the tet that holds it and
 * four barycentric weights); after each step mica_embedding_update writes its positions and
 * area-weighted normals into this program's arrays, as a renderer's vertex buffer would take
 * them. Every `every` steps the mesh is written as a Wavefront OBJ with normals,
 * <out>/render_mesh_NNNN.obj (Blender, MeshLab and ParaView open them). Each written frame
 * prints the step, the depth of the sphere and how far the vertex under it went down; the program
 * checks that this vertex follows the sphere down and that every normal is of unit length, and
 * exits 1 if not.
 *
 * usage: render_mesh [output-folder] [steps] [every]; defaults . 60 10
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include <mica/mica.h>

#include "cli.h"
#include "fine_surface.h"
#include "press_scene.h"

static const char kUsage[] =
    "usage: render_mesh [output-folder] [steps] [every]\n"
    "A 2 cm sphere pressed 15 mm into a soft 10 cm cube (6^3 cells) that wears a render mesh 16 times\n"
    "finer than its surface, bound with mica_embedding_create and placed after each step with\n"
    "mica_embedding_update (positions and normals). Writes <out>/render_mesh_NNNN.obj every `every`\n"
    "steps. Defaults: . 60 10.\n"
    "  --help  this text\n";

#define CHECK(call)                                                                                \
  do {                                                                                             \
    const mica_status s_ = (call);                                                                 \
    if (s_ < 0) {                                                                                  \
      fprintf(stderr, "%s failed: %s\n  %s\n", #call, mica_status_string(s_), mica_world_last_error(s.world)); \
      return 1;                                                                                    \
    }                                                                                              \
  } while (0)

/* The mesh as a Wavefront OBJ: positions, normals, triangles (1-based, each corner with its normal). */
static int write_obj(const char* path, const double* xyz, const double* normals, int32_t n, const int32_t* triangles,
                     int32_t t) {
  FILE* f = fopen(path, "w");
  if (!f) return 0;
  fprintf(f, "# libmica render_mesh: %d vertices, %d triangles, m\n", (int)n, (int)t);
  for (int32_t i = 0; i < n; ++i) fprintf(f, "v %.9g %.9g %.9g\n", xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]);
  for (int32_t i = 0; i < n; ++i)
    fprintf(f, "vn %.6f %.6f %.6f\n", normals[3 * i], normals[3 * i + 1], normals[3 * i + 2]);
  for (int32_t k = 0; k < t; ++k) {
    const int a = triangles[3 * k] + 1, b = triangles[3 * k + 1] + 1, c = triangles[3 * k + 2] + 1;
    fprintf(f, "f %d//%d %d//%d %d//%d\n", a, a, b, b, c, c);
  }
  return fclose(f) == 0;
}

int main(int argc, char** argv) {
  const int cli = cli_check(argc, argv, kUsage, NULL);
  if (cli >= 0) return cli;
  const char* out_dir = argc > 1 ? argv[1] : ".";
  const int steps = argc > 2 ? atoi(argv[2]) : 60;
  const int every = argc > 3 ? atoi(argv[3]) : 10;
  if (steps < 2 || every < 1) {
    fputs(kUsage, stderr);
    return 2;
  }

  /* The scene: loading for two thirds of the steps, then holding. */
  press_scene_def def = press_scene_sphere_indent_def();
  def.cells = 6;
  def.load_time = def.dt * (2 * steps / 3);
  def.hold_time = def.dt * (steps - 2 * steps / 3);
  press_scene s;
  if (press_scene_create(&def, &s) != MICA_OK) {
    fprintf(stderr, "%s\n", s.error);
    return 1;
  }

  /* The render mesh, bound once at rest. */
  fine_surface fine;
  CHECK(fine_surface_of_body(s.world, s.body, 4, &fine));
  const mica_embedding_def ed = mica_embedding_def_default();
  mica_embedding_id mesh;
  CHECK(mica_embedding_create(s.world, s.body, &ed, fine.xyz, fine.vertex_count, fine.triangles, fine.triangle_count,
                              &mesh));
  const int32_t n = fine.vertex_count;
  double* xyz = malloc(sizeof(double) * 3 * (size_t)n);
  double* normals = malloc(sizeof(double) * 3 * (size_t)n);
  if (!xyz || !normals) return 1;

  /* The vertex under the sphere: the one on the top face nearest the axis of the press. */
  int32_t top = 0;
  double best = HUGE_VAL;
  for (int32_t i = 0; i < n; ++i) {
    const double* p = fine.xyz + 3 * i;
    const double d = hypot(p[0] - s.center[0], p[2] - s.center[2]) + fabs(p[1] - s.center[1]);
    if (d < best) best = d, top = i;
  }
  printf("render mesh: %d vertices, %d triangles over %d nodes, %d tets\n", (int)n, (int)fine.triangle_count,
         (int)s.nodes, (int)s.tets);

  int ok = 1;
  for (int32_t k = 1; k <= s.steps; ++k) {
    CHECK(press_scene_step(&s, k, NULL, NULL));
    CHECK(mica_embedding_update(s.world, mesh, xyz, normals));
    for (int32_t i = 0; i < n; ++i) {
      const double length = sqrt(normals[3 * i] * normals[3 * i] + normals[3 * i + 1] * normals[3 * i + 1] +
                                 normals[3 * i + 2] * normals[3 * i + 2]);
      if (fabs(length - 1) > 1e-9) ok = 0;
    }
    if (k % every != 0 && k != s.steps) continue;
    char path[1024];
    snprintf(path, sizeof path, "%s/render_mesh_%04d.obj", out_dir, (int)k);
    if (!write_obj(path, xyz, normals, n, fine.triangles, fine.triangle_count)) {
      fprintf(stderr, "cannot write %s\n", path);
      return 1;
    }
    const double sink = fine.xyz[3 * top + 1] - xyz[3 * top + 1];
    printf("step %3d: sphere %5.2f mm deep, the vertex under it %5.2f mm down -> %s\n", (int)k,
           1e3 * press_scene_depth(&s, k), 1e3 * sink, path);
  }
  const double depth = press_scene_depth(&s, s.steps), sink = fine.xyz[3 * top + 1] - xyz[3 * top + 1];
  if (!ok) fprintf(stderr, "a normal is not of unit length\n");
  if (!(sink > 0.5 * depth)) fprintf(stderr, "the vertex under the sphere went %g m down, the sphere %g m\n", sink, depth);
  ok = ok && sink > 0.5 * depth;
  CHECK(mica_embedding_destroy(s.world, mesh));
  free(xyz);
  free(normals);
  fine_surface_free(&fine);
  press_scene_destroy(&s);
  return ok ? 0 : 1;
}
