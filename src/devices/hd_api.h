/* SPDX-License-Identifier: Apache-2.0 */
/* The part of OpenHaptics' HD API that libmica uses, declared here so that libmica builds
 * without OpenHaptics: src/devices/touch_device.cpp loads these functions at run time with
 * dlsym (it never links them), and tests/devices/fake_hd/fake_hd.c implements them.
 *
 * Types, values and signatures are those of OpenHaptics' own headers HD/hdDefines.h,
 * HD/hdDevice.h and HD/hdScheduler.h (SensAble Technologies, OpenHaptics 3.0 and 3.3, which
 * agree on every value used here), as published in public repositories such as
 * github.com/hhmai/PhantomAPI, include/HD/hdDefines.h. Only the names libmica uses are
 * declared. Plain C so that the fake can include it; on Linux HDAPIENTRY and HDCALLBACK are
 * the default C calling convention. */
#ifndef MICA_DEVICES_HD_API_H
#define MICA_DEVICES_HD_API_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef unsigned short HDushort;
typedef int HDint;
typedef double HDdouble;
typedef unsigned int HDerror;
typedef unsigned int HDenum;
typedef const char* HDstring;
typedef unsigned int HHD;

typedef struct {
  HDerror errorCode;     /* an HD_* error code below */
  int internalErrorCode; /* the device driver's own code */
  HHD hHD;               /* the device current when the error happened */
} HDErrorInfo;

typedef unsigned int HDCallbackCode;
typedef unsigned long HDSchedulerHandle;
typedef HDCallbackCode (*HDSchedulerCallback)(void* pUserData);

/* Error codes (hdDefines.h). */
#define HD_SUCCESS 0x0000
#define HD_INVALID_ENUM 0x0100
#define HD_INVALID_VALUE 0x0101
#define HD_INVALID_OPERATION 0x0102
#define HD_INVALID_INPUT_TYPE 0x0103
#define HD_BAD_HANDLE 0x0104
#define HD_WARM_MOTORS 0x0200
#define HD_EXCEEDED_MAX_FORCE 0x0201
#define HD_EXCEEDED_MAX_FORCE_IMPULSE 0x0202
#define HD_EXCEEDED_MAX_VELOCITY 0x0203
#define HD_FORCE_ERROR 0x0204
#define HD_DEVICE_FAULT 0x0300
#define HD_DEVICE_ALREADY_INITIATED 0x0301
#define HD_COMM_ERROR 0x0302
#define HD_COMM_CONFIG_ERROR 0x0303
#define HD_TIMER_ERROR 0x0304
#define HD_ILLEGAL_BEGIN 0x0400
#define HD_ILLEGAL_END 0x0401
#define HD_FRAME_ERROR 0x0402
#define HD_INVALID_PRIORITY 0x0500
#define HD_SCHEDULER_FULL 0x0501
#define HD_INVALID_LICENSE 0x0600

/* Get parameters (hdDefines.h). Lengths and units are the HD API's: mm, mm/s, N, N/mm. */
#define HD_CURRENT_BUTTONS 0x2000             /* 1 int: bit k = button k */
#define HD_CURRENT_POSITION 0x2050            /* 3 doubles, mm */
#define HD_CURRENT_VELOCITY 0x2051            /* 3 doubles, mm/s */
#define HD_CURRENT_TRANSFORM 0x2052           /* 16 doubles, column-major 4x4, translation in mm */
#define HD_DEVICE_MODEL_TYPE 0x2501           /* string */
#define HD_USABLE_WORKSPACE_DIMENSIONS 0x2551 /* 6 doubles, mm: min x, y, z, max x, y, z */
#define HD_CALIBRATION_STYLE 0x2555           /* 1 int: the HD_CALIBRATION_* styles supported */
#define HD_NOMINAL_MAX_STIFFNESS 0x2602       /* 1 double, N/mm */
#define HD_NOMINAL_MAX_FORCE 0x2603           /* 1 double, N */
#define HD_NOMINAL_MAX_CONTINUOUS_FORCE 0x2604 /* 1 double, N */
#define HD_NOMINAL_MAX_DAMPING 0x2609         /* 1 double, N s/mm */

/* Set parameters. */
#define HD_CURRENT_FORCE 0x2700 /* 3 doubles, N */

/* Capabilities for hdEnable / hdDisable. */
#define HD_FORCE_OUTPUT 0x4000

/* Scheduler (hdDefines.h: HD_MAX_SCHEDULER_PRIORITY is USHRT_MAX; hdScheduler.h). */
#define HD_MAX_SCHEDULER_PRIORITY ((HDushort)0xFFFF)
#define HD_CALLBACK_DONE 0
#define HD_CALLBACK_CONTINUE 1

/* Calibration status (hdCheckCalibration) and styles (hdUpdateCalibration). */
#define HD_CALIBRATION_OK 0x5000
#define HD_CALIBRATION_NEEDS_UPDATE 0x5001
#define HD_CALIBRATION_NEEDS_MANUAL_INPUT 0x5002
#define HD_CALIBRATION_ENCODER_RESET (1 << 0)
#define HD_CALIBRATION_AUTO (1 << 1)
#define HD_CALIBRATION_INKWELL (1 << 2)

#define HD_INVALID_HANDLE 0xFFFFFFFFu
#define HD_DEFAULT_DEVICE NULL

/* The functions (hdDevice.h, hdScheduler.h). libmica only takes their types (decltype). */
HHD hdInitDevice(HDstring pConfigName);
void hdMakeCurrentDevice(HHD hHD);
void hdDisableDevice(HHD hHD);
void hdBeginFrame(HHD hHD);
void hdEndFrame(HHD hHD);
HDErrorInfo hdGetError(void);
HDstring hdGetErrorString(HDerror errorCode);
void hdEnable(HDenum cap);
void hdDisable(HDenum cap);
void hdGetIntegerv(HDenum pname, HDint* params);
void hdGetDoublev(HDenum pname, HDdouble* params);
HDstring hdGetString(HDenum pname);
void hdSetDoublev(HDenum pname, const HDdouble* params);
HDenum hdCheckCalibration(void);
void hdUpdateCalibration(HDenum style);
void hdStartScheduler(void);
void hdStopScheduler(void);
HDSchedulerHandle hdScheduleAsynchronous(HDSchedulerCallback pCallback, void* pUserData, HDushort nPriority);
void hdUnschedule(HDSchedulerHandle hHandle);

#ifdef __cplusplus
}
#endif

#endif /* MICA_DEVICES_HD_API_H */
