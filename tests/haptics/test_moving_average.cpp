// SPDX-License-Identifier: Apache-2.0
// The servo-rate force filter: an exact moving average, restarted at contact onset (the first
// in-contact output is the raw force) and at release, with no drift over long runs and no
// allocation per sample.
#include "haptics/moving_average.hpp"
#include "alloc_counter.hpp"
#include "test_util.hpp"

using namespace mica;

namespace {

// The mean of the last min(window, k - first + 1) samples ending at k, summed oldest first.
Vec3 window_mean(const std::vector<Vec3>& x, size_t first, size_t k, int32_t window) {
  const size_t n = std::min(size_t(window), k - first + 1);
  Vec3 sum = Vec3::Zero();
  for (size_t i = k + 1 - n; i <= k; ++i) sum += x[i];
  return sum / double(n);
}

Vec3 random_vec(std::mt19937& rng, double lo, double hi) {
  std::uniform_real_distribution<double> u(lo, hi);
  return Vec3(u(rng), u(rng), u(rng));
}

void assert_vec_near(const Vec3& a, const Vec3& b, double tol, size_t k) {
  const double err = (a - b).cwiseAbs().maxCoeff();
  if (!(err <= tol)) fail_msg("sample %zu: error %.3g > %.3g", k, err, tol);
}

void assert_vec_equal(const Vec3& a, const Vec3& b, size_t k) {
  if (!(a == b)) fail_msg("sample %zu: (%.17g %.17g %.17g) != (%.17g %.17g %.17g)", k, a.x(), a.y(), a.z(), b.x(),
                          b.y(), b.z());
}

}  // namespace

static void test_matches_brute_force_window(void**) {
  std::mt19937 rng(7);
  for (int32_t window : {1, 2, 3, 20, 64}) {
    MovingAverage filter(window);
    assert_int_equal(filter.window(), window);
    std::vector<Vec3> x;
    for (size_t k = 0; k < 2000; ++k) {
      x.push_back(random_vec(rng, -1, 1));
      const Vec3 y = filter.filter(x.back(), true);
      assert_vec_near(y, window_mean(x, 0, k, window), 1e-14, k);
      assert_int_equal(filter.count(), std::min<size_t>(window, k + 1));
    }
  }
}

static void test_contact_onset_starts_a_new_window(void**) {
  std::mt19937 rng(11);
  const int32_t window = 20;
  MovingAverage filter(window);
  std::vector<Vec3> x;
  // Free motion with some noise: the window fills with out-of-contact samples.
  for (size_t k = 0; k < 50; ++k) {
    x.push_back(random_vec(rng, -0.01, 0.01));
    filter.filter(x.back(), false);
  }
  // Contact: the first output is the raw force itself, then the mean of the in-contact samples so
  // far, until the window is full and it slides.
  const size_t onset = x.size();
  for (size_t k = onset; k < onset + 3 * window; ++k) {
    x.push_back(random_vec(rng, 1, 2));
    const Vec3 y = filter.filter(x.back(), true);
    if (k == onset) assert_vec_equal(y, x.back(), k);
    assert_vec_near(y, window_mean(x, onset, k, window), 1e-14, k);
    assert_int_equal(filter.count(), std::min<size_t>(window, k - onset + 1));
  }
}

// Without the correction the window keeps averaging across the onset: N samples after it, the
// output is still the plain mean of the last N samples, out-of-contact ones included.
static void test_without_correction_the_onset_is_smeared(void**) {
  std::mt19937 rng(12);
  const int32_t window = 20;
  MovingAverage filter(window);
  filter.set_restart_on_contact_change(false);
  std::vector<Vec3> x;
  for (size_t k = 0; k < 50; ++k) {
    x.push_back(random_vec(rng, -0.01, 0.01));
    filter.filter(x.back(), false);
  }
  for (size_t k = x.size(); k < 50 + 2 * window; ++k) {
    x.push_back(random_vec(rng, 1, 2));
    const Vec3 y = filter.filter(x.back(), true);
    assert_vec_near(y, window_mean(x, 0, k, window), 1e-14, k);
    assert_int_equal(filter.count(), window);
  }
}

static void test_release_resets_the_window(void**) {
  const int32_t window = 20;
  MovingAverage filter(window);
  std::vector<Vec3> x;
  for (size_t k = 0; k < 40; ++k) {
    x.push_back(Vec3(0.5, -1.5, 2.0) + 0.01 * double(k) * Vec3::Ones());
    filter.filter(x.back(), true);
  }
  // Release: the output follows the raw force (zero) at once, not the in-contact history.
  const size_t release = x.size();
  x.push_back(Vec3::Zero());
  assert_vec_equal(filter.filter(x.back(), false), Vec3::Zero(), release);
  assert_int_equal(filter.count(), 1);
  // Then the mean of the samples since the release.
  for (size_t k = release + 1; k < release + 30; ++k) {
    x.push_back(Vec3(1e-3 * double(k % 3), 0, 0));
    assert_vec_near(filter.filter(x.back(), false), window_mean(x, release, k, window), 1e-16, k);
  }
  // A new contact restarts it again.
  assert_vec_equal(filter.filter(Vec3(0, 0, 3), true), Vec3(0, 0, 3), 0);
}

static void test_window_of_one_is_identity(void**) {
  std::mt19937 rng(3);
  MovingAverage filter(1);
  for (size_t k = 0; k < 1000; ++k) {
    const Vec3 raw = random_vec(rng, -1e3, 1e3);
    assert_vec_equal(filter.filter(raw, (k / 7) % 2 == 0), raw, k);
  }
}

static void test_no_drift_over_a_million_samples(void**) {
  // Half a million hard-contact samples (about 1000 N), then half a million light ones (about
  // 1 mN). A plain running sum keeps the rounding of the first phase forever: in the second its
  // error is large against the forces averaged. The filter's must stay at rounding level.
  std::mt19937 rng(5);
  const int32_t window = 20;
  const size_t total = 1000000;
  MovingAverage filter(window);
  std::vector<Vec3> last(static_cast<size_t>(window));  // the last `window` samples, as a ring
  Vec3 naive_sum = Vec3::Zero();                         // the control: a running sum never recomputed
  double worst = 0, naive_worst = 0;
  for (size_t k = 0; k < total; ++k) {
    const Vec3 raw = k < total / 2 ? Vec3(Vec3(1000, -250, 3) + random_vec(rng, -1, 1))
                                   : Vec3(1e-3 * (Vec3(1, -1, 2) + random_vec(rng, -0.5, 0.5)));
    Vec3& slot = last[k % size_t(window)];
    if (k >= size_t(window)) naive_sum -= slot;
    slot = raw;
    naive_sum += raw;
    const Vec3 y = filter.filter(raw, true);
    if (k >= size_t(window) && (k % 49999 == 0 || k + 1 == total)) {
      std::vector<Vec3> ordered;  // oldest first: the ring's oldest entry is the one after k's
      double scale = 0;           // the largest component in the window
      for (size_t i = 1; i <= size_t(window); ++i) {
        ordered.push_back(last[(k + i) % size_t(window)]);
        scale = std::max(scale, ordered.back().cwiseAbs().maxCoeff());
      }
      const Vec3 exact = window_mean(ordered, 0, ordered.size() - 1, window);
      worst = std::max(worst, (y - exact).cwiseAbs().maxCoeff() / scale);
      naive_worst = std::max(naive_worst, (naive_sum / double(window) - exact).cwiseAbs().maxCoeff() / scale);
    }
  }
  printf("# relative error after 1e6 samples: %.3g (a plain running sum: %.3g)\n", worst, naive_worst);
  assert_le(worst, 1e-12);
  assert_le(1e-11, naive_worst);  // the test can tell a drifting sum from an exact one
}

static void test_set_window_and_bad_windows(void**) {
  MovingAverage filter(4);
  for (int i = 0; i < 4; ++i) filter.filter(Vec3(1, 1, 1), true);
  filter.set_window(2);
  assert_int_equal(filter.window(), 2);
  assert_int_equal(filter.count(), 0);
  assert_true(filter.filter(Vec3(3, 0, 0), true) == Vec3(3, 0, 0));  // emptied: a fresh start
  assert_true(filter.filter(Vec3(5, 0, 0), true) == Vec3(4, 0, 0));
  filter.reset();
  assert_int_equal(filter.count(), 0);
  assert_true(filter.filter(Vec3(7, 0, 0), true) == Vec3(7, 0, 0));

  for (int32_t bad : {0, -1}) {
    bool thrown = false;
    try {
      MovingAverage m(bad);
    } catch (const Error& e) {
      thrown = e.code() == Errc::InvalidArgument;
    }
    assert_true(thrown);
  }
}

static void test_non_finite_sample_does_not_linger(void**) {
  MovingAverage filter(5);
  for (int i = 0; i < 5; ++i) filter.filter(Vec3(1, 2, 3), true);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const Vec3 y = filter.filter(Vec3(nan, 0, 0), true);
  assert_true(std::isnan(y.x()));  // passed on for the safety stage to zero
  // The next sample starts a clean window: no NaN in the running sum.
  assert_true(filter.filter(Vec3(2, 2, 2), true) == Vec3(2, 2, 2));
  assert_true(filter.filter(Vec3(4, 4, 4), true) == Vec3(3, 3, 3));
}

static void test_filter_does_not_allocate(void**) {
  // The counter works: a vector allocates.
  mica_test::start_counting_allocations();
  std::vector<double>* v = new std::vector<double>(100);
  const int64_t counted = mica_test::stop_counting_allocations();
  delete v;
  assert_int_equal(counted, 2);

  MovingAverage filter(20);
  std::mt19937 rng(1);
  std::vector<Vec3> x(5000);
  for (Vec3& s : x) s = random_vec(rng, -1, 1);
  Vec3 sink = Vec3::Zero();
  mica_test::start_counting_allocations();
  for (size_t k = 0; k < x.size(); ++k) sink += filter.filter(x[k], (k / 100) % 2 == 0);
  filter.reset();
  const int64_t during = mica_test::stop_counting_allocations();
  assert_int_equal(during, 0);
  assert_true(sink.allFinite());
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_matches_brute_force_window),
      cmocka_unit_test(test_contact_onset_starts_a_new_window),
      cmocka_unit_test(test_without_correction_the_onset_is_smeared),
      cmocka_unit_test(test_release_resets_the_window),
      cmocka_unit_test(test_window_of_one_is_identity),
      cmocka_unit_test(test_no_drift_over_a_million_samples),
      cmocka_unit_test(test_set_window_and_bad_windows),
      cmocka_unit_test(test_non_finite_sample_does_not_linger),
      cmocka_unit_test(test_filter_does_not_allocate),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
