// SPDX-License-Identifier: Apache-2.0
// The world's calls as a replay makes them (world/replay.cpp), with arguments that only a corrupt
// recording holds (the C API never passes them): each throws mica::Error of the expected code,
// saying what is wrong, and leaves the world exactly as it was (its saved state, byte for byte).
#include "test_util.hpp"

using namespace mica;

namespace {

// A box of 2^3 cells fixed at y = 0.
struct Scene {
  World world{WorldSettings{}};
  Id body = 0;
  Scene() {
    body = world.add_body(make_box_grid(Vec3(0, 0, 0), Vec3(0.1, 0.1, 0.1), {2, 2, 2}, 6), BodySettings{},
                          Vec3::Zero(), Vec3::Zero());
    std::vector<int32_t> base;
    for (int32_t i = 0; i < world.body(body).fem.node_count(); ++i)
      if (world.body(body).fem.rest[i].y() < 1e-9) base.push_back(i);
    world.add_lpc(body, base, LpcSpec{});
    world.step(0.01);
  }
};

// `call` must throw mica::Error with `code` and a message containing `phrase`, the world unchanged.
template <class Call>
void expect_refused(Scene& s, Call call, Errc code, const char* phrase) {
  const std::vector<uint8_t> before = s.world.save_state();
  try {
    call(s.world);
    fail_msg("the call succeeded; expected an error saying '%s'", phrase);
  } catch (const Error& e) {
    if (e.code() != code || !std::strstr(e.what(), phrase))
      fail_msg("expected error code %d saying '%s', got code %d: %s", int(code), phrase, int(e.code()), e.what());
  }
  assert_true(s.world.save_state() == before);
}

}  // namespace

static void test_node_forces_fewer_than_nodes(void**) {
  Scene s;
  expect_refused(
      s, [&](World& w) { w.set_node_forces(s.body, {0, 1}, Vec3List{Vec3(0, 1, 0)}); }, Errc::InvalidArgument,
      "2 node indices and 1 force");
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_node_forces_fewer_than_nodes),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
