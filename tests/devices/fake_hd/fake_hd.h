/* SPDX-License-Identifier: Apache-2.0 */
/* A stand-in for OpenHaptics' HD library (libfake_hd.so, test-only): the HD functions
 * libmica's Touch backend loads, over a scripted stylus, plus these controls for the tests.
 * Lengths are HD's: mm, mm/s. */
#ifndef MICA_TESTS_FAKE_HD_H
#define MICA_TESTS_FAKE_HD_H

#include "devices/hd_api.h"

#ifdef __cplusplus
extern "C" {
#endif

#define FAKE_HD_HANDLE 3u          /* what hdInitDevice returns */
#define FAKE_HD_MAX_FORCES 100000  /* forces logged; later ones are counted only */

/* Back to a fresh, calibrated, uninitialised device; the scheduler must be stopped. */
void fake_hd_reset(void);

/* Failure switches. */
void fake_hd_fail_init(HDerror code);                   /* hdInitDevice fails with it; 0: succeeds */
void fake_hd_set_calibration(HDenum status, HDint styles); /* hdCheckCalibration, HD_CALIBRATION_STYLE */
void fake_hd_set_frame_error(HDerror code);             /* pushed by every hdEndFrame; 0: none */

/* Hostile modes (issue 16): what the device reports goes wrong on every third frame (or always,
 * for the figures). The stylus script below stays as documented; these change what HD returns. */
#define FAKE_HD_HOSTILE_NONE 0
#define FAKE_HD_HOSTILE_NAN_POSE 1      /* NaN position and transform translation */
#define FAKE_HD_HOSTILE_HUGE_POSE 2     /* positions and velocities of 1e300 mm */
#define FAKE_HD_HOSTILE_BAD_ROTATION 3  /* the transform's rotation scaled by 3, zero, or a reflection */
#define FAKE_HD_HOSTILE_FIGURES 4       /* nominal max force and stiffness 1e300 */
#define FAKE_HD_HOSTILE_STALL 5         /* hdBeginFrame sleeps 50 ms every 20th frame */
void fake_hd_set_hostile(int mode);

/* The scripted stylus during frame `frame` (0 = the first hdBeginFrame): position and
 * transform translation (mm), velocity (mm/s), rotation about z by 0.001 rad a frame,
 * buttons = frame & 3. Any output may be NULL. */
void fake_hd_stylus(long frame, double position[3], double velocity[3], double transform[16], int* buttons);

/* What the library saw. */
long fake_hd_frame_count(void);         /* frames begun */
long fake_hd_force_count(void);         /* hdSetDoublev(HD_CURRENT_FORCE) calls */
int fake_hd_force(long i, double out[3]); /* the i-th force logged, 0 if out of the log */
long fake_hd_nonfinite_forces(void);    /* forces with a NaN or infinite component */
long fake_hd_misuse(void);              /* calls outside a frame, with a bad handle or unknown enum */
int fake_hd_initialized(void);
int fake_hd_force_output(void);         /* HD_FORCE_OUTPUT enabled */
const char* fake_hd_device_name(void);  /* hdInitDevice's argument; NULL for the default device */
int fake_hd_calibration_updates(void);
HDenum fake_hd_calibration_style_used(void);

/* Scheduler: hdStartScheduler runs the scheduled callbacks on a thread every 1 ms until
 * hdStopScheduler; with the manual scheduler set it starts no thread, and fake_hd_run_ticks
 * runs them n times on the calling thread instead (deterministic tests). */
void fake_hd_set_manual_scheduler(int manual);
void fake_hd_run_ticks(long n);
long fake_hd_tick_count(void);
int fake_hd_scheduler_running(void);
int fake_hd_scheduled_callbacks(void);  /* active ones */
HDushort fake_hd_last_priority(void);

#ifdef __cplusplus
}
#endif

#endif /* MICA_TESTS_FAKE_HD_H */
