/* SPDX-License-Identifier: Apache-2.0 */
/* A world's log callback that counts the warnings and keeps the last one: wd.log = capture_log,
 * wd.log_user = &a_log_capture. Include after mica.h. */
#ifndef MICA_TESTS_CAPI_LOG_CAPTURE_H
#define MICA_TESTS_CAPI_LOG_CAPTURE_H
#include <stdio.h>

typedef struct log_capture {
  int warnings;
  char last[1024];
} log_capture;

static inline void capture_log(int32_t level, const char* message, void* user) {
  log_capture* c = (log_capture*)user;
  if (level != MICA_LOG_WARNING) return;
  c->warnings++;
  snprintf(c->last, sizeof c->last, "%s", message);
}

#endif
