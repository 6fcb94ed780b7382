/* SPDX-License-Identifier: Apache-2.0 */
/* OK(world, call): the call must succeed (MICA_OK, or MICA_WARN_NOT_CONVERGED, which keeps the
 * step); otherwise the cmocka test fails, printing the call, its status and the world's message
 * (world NULL: the thread's). Include after cmocka.h and mica.h. */
#ifndef MICA_TESTS_CAPI_OK_H
#define MICA_TESTS_CAPI_OK_H

#define OK(w, call)                                                                               \
  do {                                                                                            \
    const mica_status s_ = (call);                                                                \
    if (s_ != MICA_OK && s_ != MICA_WARN_NOT_CONVERGED) {                                         \
      print_error("%s:%d: %s: %s\n  %s\n", __FILE__, __LINE__, #call, mica_status_string(s_),     \
                  mica_world_last_error(w));                                                      \
      fail();                                                                                     \
    }                                                                                             \
  } while (0)

#endif
