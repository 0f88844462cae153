/* What the V4L2 emulator (libcvo_v4l2_emulator.so, loaded with LD_PRELOAD) tells a test about one
 * of its nodes: look the function up with dlsym(RTLD_DEFAULT, "cvo_v4l2_emulator_stats"); it is
 * absent when the emulator is not loaded. */
#ifndef CVO_V4L2_EMULATOR_STATS_H
#define CVO_V4L2_EMULATOR_STATS_H
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

struct cvo_v4l2_emulator_node_stats {
  uint64_t produced;  /* frames the camera made since it was last plugged in (sequence numbers used) */
  uint64_t delivered; /* of those, filled into a buffer */
  uint64_t dropped;   /* no buffer was queued: lost, a gap in the sequence */
  uint64_t unplugs;   /* of the camera, in this process */
};

/* 0 and *out filled for an emulated node's path; -1 for any other path. */
typedef int (*cvo_v4l2_emulator_stats_fn)(const char* node, struct cvo_v4l2_emulator_node_stats* out);

#ifdef __cplusplus
}
#endif
#endif
