#include "dynamics/schedule.h"

#include <stdlib.h>
#include <string.h>

#include "core/error.h"

typedef struct scheduled_event {
	long long position_numerator; /* position = numerator / denominator, compared exactly */
	long long position_denominator;
	int order;
	int kind;
} scheduled_event;

static int compare_events(const void *left, const void *right)
{
	const scheduled_event *l = left, *r = right;
	/* Exact rational comparison: no rounding can reorder events. */
	long long lhs = l->position_numerator * r->position_denominator;
	long long rhs = r->position_numerator * l->position_denominator;
	if (lhs != rhs) {
		return lhs < rhs ? -1 : 1;
	}
	if (l->order != r->order) {
		return l->order < r->order ? -1 : 1;
	}
	return l->kind - r->kind;
}

static int iterations_per_frame(int importance, int substeps)
{
	if (importance > PLAIT_MAX_IMPORTANCE) {
		importance = PLAIT_MAX_IMPORTANCE;
	}
	return importance > substeps ? importance : substeps;
}

int plait_schedule_substep_iterations(int importance, int substeps, int substep)
{
	long long total = iterations_per_frame(importance, substeps);
	return (int)((substep + 1) * total / substeps - substep * total / substeps);
}

void plait_schedule_destroy(plait_schedule *schedule, const plait_allocator *allocator)
{
	plait_free(allocator, schedule->substep_start);
	plait_free(allocator, schedule->events);
	memset(schedule, 0, sizeof *schedule);
}

plait_result plait_schedule_build(plait_schedule *schedule, const plait_allocator *allocator, int substeps,
                                  const plait_kind_desc *kinds, int kind_count, plait_error *error)
{
	memset(schedule, 0, sizeof *schedule);
	if (substeps < 1 || kind_count < 0 || kind_count > PLAIT_MAX_KINDS) {
		return plait_error_set(error, PLAIT_ERROR_INVALID_ARGUMENT,
		                       "schedule needs substeps >= 1 and at most %d kinds", PLAIT_MAX_KINDS);
	}
	int event_count = 0;
	int max_per_substep = 0;
	for (int s = 0; s < substeps; ++s) {
		int in_substep = 0;
		for (int k = 0; k < kind_count; ++k) {
			in_substep += plait_schedule_substep_iterations(kinds[k].importance, substeps, s);
		}
		event_count += in_substep;
		max_per_substep = in_substep > max_per_substep ? in_substep : max_per_substep;
	}
	schedule->substep_count = substeps;
	schedule->event_count = event_count;
	schedule->substep_start = plait_alloc_zero(allocator, (size_t)substeps + 1, sizeof(int));
	schedule->events = event_count > 0 ? plait_alloc_zero(allocator, (size_t)event_count, sizeof(int)) : NULL;
	scheduled_event *scratch =
	    max_per_substep > 0 ? plait_alloc_zero(allocator, (size_t)max_per_substep, sizeof *scratch) : NULL;
	if (schedule->substep_start == NULL ||
	    (event_count > 0 && (schedule->events == NULL || scratch == NULL))) {
		plait_free(allocator, scratch);
		plait_schedule_destroy(schedule, allocator);
		return plait_error_set(error, PLAIT_ERROR_OUT_OF_MEMORY, "out of memory building the schedule");
	}

	int written = 0;
	for (int s = 0; s < substeps; ++s) {
		schedule->substep_start[s] = written;
		int count = 0;
		for (int k = 0; k < kind_count; ++k) {
			int n = plait_schedule_substep_iterations(kinds[k].importance, substeps, s);
			for (int j = 0; j < n; ++j) {
				scratch[count++] = (scheduled_event){j + 1, n, kinds[k].order, k};
			}
		}
		if (count > 1) {
			qsort(scratch, (size_t)count, sizeof *scratch, compare_events);
		}
		for (int e = 0; e < count; ++e) {
			schedule->events[written++] = scratch[e].kind;
		}
	}
	schedule->substep_start[substeps] = written;
	plait_free(allocator, scratch);
	return PLAIT_OK;
}
