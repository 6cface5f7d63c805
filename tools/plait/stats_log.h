/* DIR/stats.jsonl: one JSON object per frame, for plots and regression checks. */
#ifndef PLAIT_STATS_LOG_H
#define PLAIT_STATS_LOG_H

#include "files.h"

#include <plait/plait.h>

typedef struct plait_stats_log {
	plait_atomic_file file;
} plait_stats_log;

bool plait_stats_log_open(plait_stats_log *log, const char *dir, plait_tool_error *error);
/* {"frame":F,"ms":M,"kinetic_energy":..,"max_strain":..,"penetrations":..,"nonfinite":..,"contacts":..,
 *  "ccd_hits":..,"failsafe":..,"collision_ms":..};
 * frame replaces stats.frame (frame 0 is logged before any step); non-finite numbers become null. */
/* check may be NULL; when given, its counts are written as "intersections" and
 * "inside_colliders". */
bool plait_stats_log_write(plait_stats_log *log, int frame, double step_ms, const plait_frame_stats *stats,
                           const plait_intersection_report *check, plait_tool_error *error);
/* Renames the log into place with every line written so far. */
bool plait_stats_log_close(plait_stats_log *log, plait_tool_error *error);

#endif
