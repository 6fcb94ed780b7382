// SPDX-License-Identifier: Apache-2.0
// SlotMap: ids with kind and generation, and lookups from other threads while the owning thread
// inserts and erases (issue 16: mica_device_get_stats on a reader thread freed under it by
// mica_device_create's reallocation). Labelled `threads`: CI runs it under ThreadSanitizer, and
// the address-sanitizer build reports a use after free should storage move again.
#include "test_util.hpp"

#include <atomic>
#include <chrono>
#include <thread>

using namespace mica;

namespace {

struct Item {
  explicit Item(int v, std::atomic<int>* alive = nullptr) : value(v), alive_(alive) {
    if (alive_) alive_->fetch_add(1);
  }
  ~Item() {
    if (alive_) alive_->fetch_sub(1);
    value = -1;
  }
  int value;
  std::atomic<int>* alive_;
};

using Map = SlotMap<Item, IdKind::Device>;

}  // namespace

static void test_ids_are_checked(void**) {
  Map map;
  const Id a = map.insert(std::make_unique<Item>(1));
  const Id b = map.insert(std::make_unique<Item>(2));
  assert_int_equal(map.find(a)->value, 1);
  assert_int_equal(map.find(b)->value, 2);
  assert_null(map.find(0));
  assert_null(map.find((a & ~(uint64_t(0xff) << 56)) | (uint64_t(IdKind::Body) << 56)));  // another kind
  assert_null(map.find(a + 1000));                                                       // no such slot
  map.erase(a);
  assert_null(map.find(a));
  const Id c = map.insert(std::make_unique<Item>(3));  // reuses a's slot, with a new generation
  assert_true((c & 0xffffffffu) == (a & 0xffffffffu));
  assert_true(c != a);
  assert_null(map.find(a));
  assert_int_equal(map.find(c)->value, 3);
  int seen = 0;
  map.for_each([&](Id, Item& item) { seen += item.value; });
  assert_int_equal(seen, 5);
}

// Readers look up a fixed object and the newest ones while the owner inserts thousands (the old
// vector of slots reallocated under them) and erases some.
static void test_find_while_the_owner_inserts(void**) {
  Map map;
  const Id first = map.insert(std::make_unique<Item>(7));
  std::atomic<Id> newest{first};
  std::atomic<bool> done{false};
  std::atomic<int> started{0};
  auto reader = [&] {
    started.fetch_add(1);
    while (!done.load(std::memory_order_acquire)) {
      const Map::ReadGuard guard(map);
      const Item* f = map.find(first);
      if (!f || f->value != 7) std::abort();
      // The newest may be gone already; if found, it is alive while the guard is held.
      if (const Item* x = map.find(newest.load(std::memory_order_acquire)); x && x->value < 0) std::abort();
    }
  };
  std::thread r1(reader), r2(reader);
  while (started.load() < 2) std::this_thread::yield();  // both read while the owner inserts
  std::vector<Id> ids;
  for (int i = 0; i < 3000; ++i) {
    ids.push_back(map.insert(std::make_unique<Item>(i)));
    newest.store(ids.back(), std::memory_order_release);
    if (i % 3 == 0) {
      map.erase(ids[size_t(i) / 2]);
    }
  }
  done.store(true, std::memory_order_release);
  r1.join();
  r2.join();
  assert_non_null(map.find(first));
}

// erase() deletes an object only after the readers that may hold it have closed their guards.
static void test_erase_waits_for_readers(void**) {
  Map map;
  std::atomic<int> alive{0};
  const Id id = map.insert(std::make_unique<Item>(42, &alive));
  std::atomic<bool> holding{false}, erased{false};
  std::atomic<int> value_seen{0};
  std::thread reader([&] {
    const Map::ReadGuard guard(map);
    const Item* item = map.find(id);
    holding.store(true);
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    value_seen.store(item ? item->value : -2);  // still alive: erase waits for this guard
  });
  while (!holding.load()) std::this_thread::yield();
  map.erase(id);
  erased.store(true);
  reader.join();
  assert_int_equal(value_seen.load(), 42);
  assert_int_equal(alive.load(), 0);
  assert_null(map.find(id));
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_ids_are_checked),
      cmocka_unit_test(test_find_while_the_owner_inserts),
      cmocka_unit_test(test_erase_waits_for_readers),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
