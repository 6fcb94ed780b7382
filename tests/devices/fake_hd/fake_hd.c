/* SPDX-License-Identifier: Apache-2.0 */
/* The fake HD library: see fake_hd.h. Every HD call locks `state_lock`; the scheduler's
 * callbacks run under `schedule_lock` and take `state_lock` inside it, never the reverse. */
#include "fake_hd.h"

#include <math.h>
#include <pthread.h>
#include <string.h>
#include <time.h>

#define MAX_ERRORS 16
#define MAX_CALLBACKS 8

static pthread_mutex_t state_lock = PTHREAD_MUTEX_INITIALIZER;
static pthread_mutex_t schedule_lock = PTHREAD_MUTEX_INITIALIZER;

static struct {
  int initialized;
  char device_name[64];
  int named;
  HDerror init_error;
  HDenum calibration;
  HDint calibration_styles;
  int calibration_updates;
  HDenum calibration_style_used;
  int force_output;
  int in_frame;
  long frame;  /* the frame in progress */
  long frames; /* frames begun */
  HDerror frame_error;
  HDErrorInfo errors[MAX_ERRORS]; /* a stack: the last is the most recent */
  int error_count;
  long force_count;
  long nonfinite_forces;
  long misuse;
} fake;

static double forces[FAKE_HD_MAX_FORCES][3];
static int hostile; /* FAKE_HD_HOSTILE_* */

static struct {
  HDSchedulerCallback callback;
  void* data;
  int active;
} callbacks[MAX_CALLBACKS];
static int callback_count;
static int running;
static int manual_scheduler; /* hdStartScheduler starts no thread: fake_hd_run_ticks drives */
static int thread_started;
static pthread_t scheduler_thread;
static long ticks;
static HDushort last_priority;

/* ---- helpers, state_lock held */

static void push_error(HDerror code) {
  if (fake.error_count == MAX_ERRORS) { /* full: forget the oldest */
    memmove(fake.errors, fake.errors + 1, (MAX_ERRORS - 1) * sizeof fake.errors[0]);
    --fake.error_count;
  }
  fake.errors[fake.error_count].errorCode = code;
  fake.errors[fake.error_count].internalErrorCode = 0;
  fake.errors[fake.error_count].hHD = FAKE_HD_HANDLE;
  ++fake.error_count;
}

static void misuse(HDerror code) {
  ++fake.misuse;
  push_error(code);
}

static int good_handle(HHD h) {
  if (fake.initialized && h == FAKE_HD_HANDLE) return 1;
  misuse(HD_BAD_HANDLE);
  return 0;
}

static int need_frame(void) {
  if (fake.in_frame) return 1;
  misuse(HD_INVALID_OPERATION);
  return 0;
}

/* ---- the scripted stylus */

void fake_hd_stylus(long frame, double position[3], double velocity[3], double transform[16], int* buttons) {
  const double n = (double)frame;
  const double p[3] = {1.5 * n, 10 - 2.25 * n, 40 + 0.5 * n};
  if (position) memcpy(position, p, sizeof p);
  if (velocity) {
    velocity[0] = 1500;
    velocity[1] = -2250;
    velocity[2] = 500;
  }
  if (transform) {
    const double c = cos(0.001 * n), s = sin(0.001 * n);
    const double m[16] = {c, s, 0, 0, -s, c, 0, 0, 0, 0, 1, 0, p[0], p[1], p[2], 1}; /* column-major */
    memcpy(transform, m, sizeof m);
  }
  if (buttons) *buttons = (int)(frame & 3);
}

/* ---- the HD API */

HHD hdInitDevice(HDstring pConfigName) {
  HHD h = HD_INVALID_HANDLE;
  pthread_mutex_lock(&state_lock);
  fake.named = pConfigName != NULL;
  if (pConfigName) {
    strncpy(fake.device_name, pConfigName, sizeof fake.device_name - 1);
    fake.device_name[sizeof fake.device_name - 1] = '\0';
  }
  if (fake.init_error != HD_SUCCESS)
    push_error(fake.init_error);
  else if (fake.initialized)
    push_error(HD_DEVICE_ALREADY_INITIATED);
  else {
    fake.initialized = 1;
    h = FAKE_HD_HANDLE;
  }
  pthread_mutex_unlock(&state_lock);
  return h;
}

void hdMakeCurrentDevice(HHD hHD) {
  pthread_mutex_lock(&state_lock);
  good_handle(hHD);
  pthread_mutex_unlock(&state_lock);
}

void hdDisableDevice(HHD hHD) {
  pthread_mutex_lock(&state_lock);
  if (good_handle(hHD)) fake.initialized = 0;
  pthread_mutex_unlock(&state_lock);
}

void hdBeginFrame(HHD hHD) {
  if (hostile == FAKE_HD_HOSTILE_STALL && fake.frames % 20 == 19) {
    const struct timespec pause = {0, 50 * 1000 * 1000};
    nanosleep(&pause, NULL);
  }
  pthread_mutex_lock(&state_lock);
  if (!good_handle(hHD)) {
  } else if (fake.in_frame) {
    misuse(HD_ILLEGAL_BEGIN);
  } else {
    fake.in_frame = 1;
    fake.frame = fake.frames++;
  }
  pthread_mutex_unlock(&state_lock);
}

void hdEndFrame(HHD hHD) {
  pthread_mutex_lock(&state_lock);
  if (!good_handle(hHD)) {
  } else if (!fake.in_frame) {
    misuse(HD_ILLEGAL_END);
  } else {
    fake.in_frame = 0;
    if (fake.frame_error != HD_SUCCESS) push_error(fake.frame_error);
  }
  pthread_mutex_unlock(&state_lock);
}

HDErrorInfo hdGetError(void) {
  HDErrorInfo e = {HD_SUCCESS, 0, FAKE_HD_HANDLE};
  pthread_mutex_lock(&state_lock);
  if (fake.error_count > 0) e = fake.errors[--fake.error_count];
  pthread_mutex_unlock(&state_lock);
  return e;
}

HDstring hdGetErrorString(HDerror errorCode) {
  switch (errorCode) {
    case HD_SUCCESS: return "fake HD: no error";
    case HD_WARM_MOTORS: return "fake HD: warm motors";
    case HD_COMM_ERROR: return "fake HD: communication error";
    default: return "fake HD: error";
  }
}

void hdEnable(HDenum cap) {
  pthread_mutex_lock(&state_lock);
  if (cap == HD_FORCE_OUTPUT)
    fake.force_output = 1;
  else
    misuse(HD_INVALID_ENUM);
  pthread_mutex_unlock(&state_lock);
}

void hdDisable(HDenum cap) {
  pthread_mutex_lock(&state_lock);
  if (cap == HD_FORCE_OUTPUT)
    fake.force_output = 0;
  else
    misuse(HD_INVALID_ENUM);
  pthread_mutex_unlock(&state_lock);
}

void hdGetIntegerv(HDenum pname, HDint* params) {
  pthread_mutex_lock(&state_lock);
  if (pname == HD_CURRENT_BUTTONS) {
    if (need_frame()) fake_hd_stylus(fake.frame, NULL, NULL, NULL, params);
  } else if (pname == HD_CALIBRATION_STYLE) {
    *params = fake.calibration_styles;
  } else {
    misuse(HD_INVALID_ENUM);
  }
  pthread_mutex_unlock(&state_lock);
}

void hdGetDoublev(HDenum pname, HDdouble* params) {
  /* The Touch's published figures: 3.3 N peak, 0.88 N continuous, 160 x 120 x 70 mm. */
  static const double workspace[6] = {-80, -60, -35, 80, 60, 35};
  pthread_mutex_lock(&state_lock);
  switch (pname) {
    case HD_CURRENT_POSITION:
      if (need_frame()) {
        fake_hd_stylus(fake.frame, params, NULL, NULL, NULL);
        if (hostile == FAKE_HD_HOSTILE_NAN_POSE && fake.frame % 3 == 2) params[0] = NAN;
        if (hostile == FAKE_HD_HOSTILE_HUGE_POSE && fake.frame % 3 == 2) params[1] = 1e300;
      }
      break;
    case HD_CURRENT_VELOCITY:
      if (need_frame()) {
        fake_hd_stylus(fake.frame, NULL, params, NULL, NULL);
        if (hostile == FAKE_HD_HOSTILE_HUGE_POSE && fake.frame % 3 == 2) params[2] = -1e300;
      }
      break;
    case HD_CURRENT_TRANSFORM:
      if (need_frame()) {
        fake_hd_stylus(fake.frame, NULL, NULL, params, NULL);
        if (hostile == FAKE_HD_HOSTILE_NAN_POSE && fake.frame % 3 == 2) params[13] = NAN;
        if (hostile == FAKE_HD_HOSTILE_HUGE_POSE && fake.frame % 3 == 2) params[13] = 1e300;
        if (hostile == FAKE_HD_HOSTILE_BAD_ROTATION && fake.frame % 3 == 2) {
          const int kind = (int)(fake.frame / 3 % 3);
          for (int c = 0; c < 3; ++c)
            for (int r = 0; r < 3; ++r) {
              double* m = &params[4 * c + r];
              *m = kind == 0 ? 3 * *m : kind == 1 ? 0 : (c == 2 ? -*m : *m); /* scaled, zero, reflected */
            }
        }
      }
      break;
    case HD_NOMINAL_MAX_FORCE: params[0] = hostile == FAKE_HD_HOSTILE_FIGURES ? 1e300 : 3.3; break;
    case HD_NOMINAL_MAX_CONTINUOUS_FORCE: params[0] = 0.88; break;
    case HD_NOMINAL_MAX_STIFFNESS: params[0] = hostile == FAKE_HD_HOSTILE_FIGURES ? 1e300 : 1.25; break;  /* N/mm */
    case HD_NOMINAL_MAX_DAMPING: params[0] = 0.0025; break;  /* N s/mm */
    case HD_USABLE_WORKSPACE_DIMENSIONS: memcpy(params, workspace, sizeof workspace); break;
    default: misuse(HD_INVALID_ENUM);
  }
  pthread_mutex_unlock(&state_lock);
}

HDstring hdGetString(HDenum pname) {
  if (pname == HD_DEVICE_MODEL_TYPE) return "Fake Touch";
  pthread_mutex_lock(&state_lock);
  misuse(HD_INVALID_ENUM);
  pthread_mutex_unlock(&state_lock);
  return NULL;
}

void hdSetDoublev(HDenum pname, const HDdouble* params) {
  pthread_mutex_lock(&state_lock);
  if (pname != HD_CURRENT_FORCE) {
    misuse(HD_INVALID_ENUM);
  } else if (need_frame()) {
    if (!isfinite(params[0]) || !isfinite(params[1]) || !isfinite(params[2])) ++fake.nonfinite_forces;
    if (fake.force_count < FAKE_HD_MAX_FORCES) memcpy(forces[fake.force_count], params, sizeof forces[0]);
    ++fake.force_count;
  }
  pthread_mutex_unlock(&state_lock);
}

HDenum hdCheckCalibration(void) {
  pthread_mutex_lock(&state_lock);
  const HDenum status = fake.calibration;
  pthread_mutex_unlock(&state_lock);
  return status;
}

void hdUpdateCalibration(HDenum style) {
  pthread_mutex_lock(&state_lock);
  ++fake.calibration_updates;
  fake.calibration_style_used = style;
  /* Manual input stays needed: only a person can put the stylus in the inkwell. */
  if (fake.calibration == HD_CALIBRATION_NEEDS_UPDATE) fake.calibration = HD_CALIBRATION_OK;
  pthread_mutex_unlock(&state_lock);
}

/* ---- scheduler */

static void run_tick(void) {
  pthread_mutex_lock(&schedule_lock);
  for (int i = 0; i < callback_count; ++i)
    if (callbacks[i].active && callbacks[i].callback(callbacks[i].data) == HD_CALLBACK_DONE) callbacks[i].active = 0;
  ++ticks;
  pthread_mutex_unlock(&schedule_lock);
}

static void* scheduler_main(void* unused) {
  (void)unused;
  const struct timespec period = {0, 1000000};
  while (__atomic_load_n(&running, __ATOMIC_ACQUIRE)) {
    run_tick();
    nanosleep(&period, NULL);
  }
  return NULL;
}

void hdStartScheduler(void) {
  if (__atomic_load_n(&running, __ATOMIC_ACQUIRE)) return;
  __atomic_store_n(&running, 1, __ATOMIC_RELEASE);
  if (manual_scheduler) return;
  thread_started = pthread_create(&scheduler_thread, NULL, scheduler_main, NULL) == 0;
  if (!thread_started) {
    __atomic_store_n(&running, 0, __ATOMIC_RELEASE);
    pthread_mutex_lock(&state_lock);
    push_error(HD_TIMER_ERROR);
    pthread_mutex_unlock(&state_lock);
  }
}

void hdStopScheduler(void) {
  if (!__atomic_load_n(&running, __ATOMIC_ACQUIRE)) return;
  __atomic_store_n(&running, 0, __ATOMIC_RELEASE);
  if (thread_started) pthread_join(scheduler_thread, NULL);
  thread_started = 0;
}

HDSchedulerHandle hdScheduleAsynchronous(HDSchedulerCallback pCallback, void* pUserData, HDushort nPriority) {
  HDSchedulerHandle handle = 0;
  pthread_mutex_lock(&schedule_lock);
  last_priority = nPriority;
  if (callback_count < MAX_CALLBACKS) {
    callbacks[callback_count].callback = pCallback;
    callbacks[callback_count].data = pUserData;
    callbacks[callback_count].active = 1;
    handle = (HDSchedulerHandle)++callback_count;
  }
  pthread_mutex_unlock(&schedule_lock);
  if (handle == 0) {
    pthread_mutex_lock(&state_lock);
    push_error(HD_SCHEDULER_FULL);
    pthread_mutex_unlock(&state_lock);
  }
  return handle;
}

void hdUnschedule(HDSchedulerHandle hHandle) {
  int bad = 0;
  pthread_mutex_lock(&schedule_lock);
  if (hHandle >= 1 && hHandle <= (HDSchedulerHandle)callback_count)
    callbacks[hHandle - 1].active = 0;
  else
    bad = 1;
  pthread_mutex_unlock(&schedule_lock);
  if (bad) {
    pthread_mutex_lock(&state_lock);
    misuse(HD_INVALID_OPERATION);
    pthread_mutex_unlock(&state_lock);
  }
}

/* ---- controls */

void fake_hd_reset(void) {
  pthread_mutex_lock(&schedule_lock);
  memset(callbacks, 0, sizeof callbacks);
  callback_count = 0;
  ticks = 0;
  last_priority = 0;
  manual_scheduler = 0;
  pthread_mutex_unlock(&schedule_lock);
  pthread_mutex_lock(&state_lock);
  memset(&fake, 0, sizeof fake);
  hostile = FAKE_HD_HOSTILE_NONE;
  fake.calibration = HD_CALIBRATION_OK;
  fake.calibration_styles = HD_CALIBRATION_INKWELL;
  pthread_mutex_unlock(&state_lock);
}

#define FAKE_HD_SET(name, type, field)    \
  void name(type value) {                 \
    pthread_mutex_lock(&state_lock);      \
    fake.field = value;                   \
    pthread_mutex_unlock(&state_lock);    \
  }
#define FAKE_HD_GET(name, type, expr)     \
  type name(void) {                       \
    pthread_mutex_lock(&state_lock);      \
    const type value = (expr);            \
    pthread_mutex_unlock(&state_lock);    \
    return value;                         \
  }

FAKE_HD_SET(fake_hd_fail_init, HDerror, init_error)
FAKE_HD_SET(fake_hd_set_frame_error, HDerror, frame_error)
FAKE_HD_GET(fake_hd_frame_count, long, fake.frames)
FAKE_HD_GET(fake_hd_force_count, long, fake.force_count)
FAKE_HD_GET(fake_hd_nonfinite_forces, long, fake.nonfinite_forces)
FAKE_HD_GET(fake_hd_misuse, long, fake.misuse)
FAKE_HD_GET(fake_hd_initialized, int, fake.initialized)
FAKE_HD_GET(fake_hd_force_output, int, fake.force_output)
FAKE_HD_GET(fake_hd_calibration_updates, int, fake.calibration_updates)
FAKE_HD_GET(fake_hd_calibration_style_used, HDenum, fake.calibration_style_used)

void fake_hd_set_calibration(HDenum status, HDint styles) {
  pthread_mutex_lock(&state_lock);
  fake.calibration = status;
  fake.calibration_styles = styles;
  pthread_mutex_unlock(&state_lock);
}

int fake_hd_force(long i, double out[3]) {
  int found = 0;
  pthread_mutex_lock(&state_lock);
  if (i >= 0 && i < fake.force_count && i < FAKE_HD_MAX_FORCES) {
    memcpy(out, forces[i], sizeof forces[0]);
    found = 1;
  }
  pthread_mutex_unlock(&state_lock);
  return found;
}

const char* fake_hd_device_name(void) { return fake.named ? fake.device_name : NULL; }

void fake_hd_set_manual_scheduler(int manual) { manual_scheduler = manual; }

void fake_hd_run_ticks(long n) {
  for (long i = 0; i < n; ++i) run_tick();
}

long fake_hd_tick_count(void) {
  pthread_mutex_lock(&schedule_lock);
  const long n = ticks;
  pthread_mutex_unlock(&schedule_lock);
  return n;
}

int fake_hd_scheduler_running(void) { return __atomic_load_n(&running, __ATOMIC_ACQUIRE); }

int fake_hd_scheduled_callbacks(void) {
  int n = 0;
  pthread_mutex_lock(&schedule_lock);
  for (int i = 0; i < callback_count; ++i) n += callbacks[i].active;
  pthread_mutex_unlock(&schedule_lock);
  return n;
}

HDushort fake_hd_last_priority(void) {
  pthread_mutex_lock(&schedule_lock);
  const HDushort p = last_priority;
  pthread_mutex_unlock(&schedule_lock);
  return p;
}

void fake_hd_set_hostile(int mode) { hostile = mode; }
