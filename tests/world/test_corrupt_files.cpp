// SPDX-License-Identifier: Apache-2.0
// The world fed what a corrupt file from someone else holds: the calls a replay makes from a
// corrupt recording (world/replay.cpp; arguments the C API never passes), and an altered saved
// state whose checksum was made right again. Each is refused with mica::Error of the expected
// code, saying what is wrong, and leaves the world exactly as it was (its saved state, byte for
// byte).
#include "core/byte_stream.hpp"
#include "test_util.hpp"  // after the core's headers: cmocka defines fail()

using namespace mica;

namespace {

// A box of 2^3 cells fixed at y = 0, stepped once.
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

// A recording's node forces entry with fewer forces than node indices.
static void test_node_forces_fewer_than_nodes(void**) {
  Scene s;
  expect_refused(
      s, [&](World& w) { w.set_node_forces(s.body, {0, 1}, Vec3List{Vec3(0, 1, 0)}); }, Errc::InvalidArgument,
      "2 node indices and 1 force");
}

// A state whose statistics flag (converged) is 2: a bool holding 2 is undefined behaviour to read.
static void test_state_statistics_flag_not_a_bool(void**) {
  Scene s;
  std::vector<uint8_t> state = s.world.save_state();
  // The statistics as they are in the state, found by their bytes.
  const auto* stats = reinterpret_cast<const uint8_t*>(&s.world.stats());
  const auto at = std::search(state.begin(), state.end(), stats, stats + sizeof(WorldStats));
  assert_true(at != state.end());
  at[offsetof(WorldStats, converged)] = 2;
  // world/state_io.cpp's header: magic, version, layout, size, then the checksum of what follows.
  constexpr size_t kHeaderBytes = 32, kChecksumAt = 24;
  const uint64_t sum = fnv1a(state.data() + kHeaderBytes, state.size() - kHeaderBytes);
  std::memcpy(&state[kChecksumAt], &sum, sizeof sum);
  expect_refused(
      s, [&](World& w) { w.restore_state(state.data(), state.size()); }, Errc::Parse, "flags are not 0 or 1");
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_node_forces_fewer_than_nodes),
      cmocka_unit_test(test_state_statistics_flag_not_a_bool),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
