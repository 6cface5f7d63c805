#include "stats_log.h"

#include <math.h>
#include <stdio.h>

bool plait_stats_log_open(plait_stats_log *log, const char *dir, plait_tool_error *error)
{
	return plait_atomic_open(&log->file, dir, "stats.jsonl", error);
}

// JSON has no NaN or infinity.
static void plait_json_number(FILE *f, double v)
{
	if (isfinite(v))
		fprintf(f, "%.9g", v);
	else
		fputs("null", f);
}

bool plait_stats_log_write(plait_stats_log *log, int frame, double step_ms, const plait_frame_stats *stats,
                           const plait_intersection_report *check, plait_tool_error *error)
{
	FILE *f = log->file.file;
	fprintf(f, "{\"frame\":%d,\"ms\":", frame);
	plait_json_number(f, step_ms);
	fputs(",\"kinetic_energy\":", f);
	plait_json_number(f, stats->kinetic_energy);
	fputs(",\"max_strain\":", f);
	plait_json_number(f, stats->max_strain);
	fprintf(f, ",\"penetrations\":%d,\"nonfinite\":%d,\"contacts\":%d", stats->penetrations, stats->nonfinite,
	        stats->contacts);
	fprintf(f, ",\"ccd_hits\":%d,\"failsafe\":%d,\"tangles\":%d,\"collision_ms\":", stats->ccd_hits,
	        stats->failsafe, stats->tangles);
	plait_json_number(f, stats->collision_ms);
	if (check != NULL)
		fprintf(f, ",\"intersections\":%d,\"inside_colliders\":%d", check->triangle_pairs,
		        check->inside_colliders);
	fputs("}\n", f);
	if (ferror(f))
		return plait_tool_error_set(error, "%s: cannot write", log->file.temp_path);
	return true;
}

bool plait_stats_log_close(plait_stats_log *log, plait_tool_error *error)
{
	if (log->file.file == NULL)
		return true;
	return plait_atomic_commit(&log->file, error);
}
