// SPDX-License-Identifier: Apache-2.0
// A saved state from someone else, altered, its checksum made right again: restore_state refuses
// what the world cannot take (Errc::Parse, naming it), the world exactly as it was.
#include "core/byte_stream.hpp"
#include "test_util.hpp"  // after the core's headers: cmocka defines fail()

using namespace mica;

namespace {

// world/state_io.cpp's header: magic, version, layout, size, then the checksum of what follows.
constexpr size_t kHeaderBytes = 32, kChecksumAt = 24;

void fix_checksum(std::vector<uint8_t>& state) {
  const uint64_t sum = fnv1a(state.data() + kHeaderBytes, state.size() - kHeaderBytes);
  std::memcpy(&state[kChecksumAt], &sum, sizeof sum);
}

// A box of 2^3 cells fixed at y = 0, stepped once.
World stepped_world() {
  World w{WorldSettings{}};
  const Id body = w.add_body(make_box_grid(Vec3(0, 0, 0), Vec3(0.1, 0.1, 0.1), {2, 2, 2}, 6), BodySettings{},
                             Vec3::Zero(), Vec3::Zero());
  std::vector<int32_t> base;
  for (int32_t i = 0; i < w.body(body).fem.node_count(); ++i)
    if (w.body(body).fem.rest[i].y() < 1e-9) base.push_back(i);
  w.add_lpc(body, base, LpcSpec{});
  w.step(0.01);
  return w;
}

}  // namespace

// The statistics' flags (converged, out_of_time) are bools: a byte of 2 is refused.
static void test_statistics_flag_not_a_bool(void**) {
  World w = stepped_world();
  std::vector<uint8_t> state = w.save_state();
  // The statistics as they are in the state, found by their bytes.
  const WorldStats& stats = w.stats();
  const auto* bytes = reinterpret_cast<const uint8_t*>(&stats);
  const auto at = std::search(state.begin() + kHeaderBytes, state.end(), bytes, bytes + sizeof stats);
  assert_true(at != state.end());
  at[offsetof(WorldStats, converged)] = 2;
  fix_checksum(state);
  const std::vector<uint8_t> before = w.save_state();
  try {
    w.restore_state(state.data(), state.size());
    fail_msg("a state whose 'converged' flag is 2 was restored");
  } catch (const Error& e) {
    assert_int_equal(int(e.code()), int(Errc::Parse));
    assert_non_null(std::strstr(e.what(), "flags"));
  }
  assert_true(w.save_state() == before);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_statistics_flag_not_a_bool),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
