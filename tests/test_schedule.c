/* The scheduler rules of paper §6 and seed 000 §4.1, §4.2, §9. */
#include <criterion/criterion.h>
#include <string.h>

#include "dynamics/schedule.h"

static const plait_allocator heap = {0};

typedef struct counts {
	int stretch, collision, events;
} counts;

/* Builds stretch (order 10) and collision (order 100) and counts them over the frame. */
static plait_schedule build(int substeps, int stretch, int collision)
{
	plait_kind_desc kinds[2] = {{"stretch", 10, stretch}, {"collision", 100, collision}};
	plait_schedule schedule;
	cr_assert_eq(plait_schedule_build(&schedule, &heap, substeps, kinds, 2, NULL), PLAIT_OK);
	return schedule;
}

static counts count_frame(const plait_schedule *s)
{
	counts c = {0};
	for (int e = 0; e < s->event_count; ++e) {
		c.stretch += s->events[e] == 0;
		c.collision += s->events[e] == 1;
	}
	c.events = s->event_count;
	return c;
}

Test(schedule, stretch_20_collision_4_gives_one_collision_per_5_stretches_up_to_4_substeps)
{
	for (int substeps = 1; substeps <= 4; ++substeps) {
		plait_schedule s = build(substeps, 20, 4);
		counts c = count_frame(&s);
		cr_assert_eq(c.stretch, 20, "substeps %d", substeps);
		cr_assert_eq(c.collision, 4, "substeps %d", substeps);
		/* Between consecutive collisions (and before the first) there are 5 stretches when
		 * substeps divide evenly; in every case the per-frame ratio is 5:1. */
		if (4 % substeps == 0) {
			int run = 0;
			for (int e = 0; e < s.event_count; ++e) {
				if (s.events[e] == 0) {
					++run;
				} else {
					cr_assert_eq(run, 5, "substeps %d: %d stretches before a collision", substeps, run);
					run = 0;
				}
			}
		}
		plait_schedule_destroy(&s, &heap);
	}
}

Test(schedule, substeps_10_give_10_collisions_per_frame_one_per_2_stretches)
{
	plait_schedule s = build(10, 20, 4);
	counts c = count_frame(&s);
	cr_assert_eq(c.collision, 10);
	cr_assert_eq(c.stretch, 20);
	for (int sub = 0; sub < 10; ++sub) {
		int first = s.substep_start[sub], n = s.substep_start[sub + 1] - first;
		cr_assert_eq(n, 3);
		cr_assert_eq(s.events[first + 0], 0);
		cr_assert_eq(s.events[first + 1], 0);
		cr_assert_eq(s.events[first + 2], 1);
	}
	plait_schedule_destroy(&s, &heap);
}

Test(schedule, substeps_30_give_30_of_each)
{
	plait_schedule s = build(30, 20, 4);
	counts c = count_frame(&s);
	cr_assert_eq(c.collision, 30);
	cr_assert_eq(c.stretch, 30);
	for (int sub = 0; sub < 30; ++sub) {
		cr_assert_eq(s.substep_start[sub + 1] - s.substep_start[sub], 2);
		cr_assert_eq(s.events[s.substep_start[sub]], 0);
		cr_assert_eq(s.events[s.substep_start[sub] + 1], 1);
	}
	plait_schedule_destroy(&s, &heap);
}

Test(schedule, every_kind_runs_every_substep_and_collision_is_last)
{
	plait_kind_desc kinds[4] = {
	    {"stretch", 10, 37}, {"shear", 20, 3}, {"bend", 30, 1}, {"collision", 100, 7}};
	for (int substeps = 1; substeps <= 12; ++substeps) {
		plait_schedule s;
		cr_assert_eq(plait_schedule_build(&s, &heap, substeps, kinds, 4, NULL), PLAIT_OK);
		int total[4] = {0};
		for (int sub = 0; sub < substeps; ++sub) {
			int seen[4] = {0};
			int first = s.substep_start[sub], last = s.substep_start[sub + 1];
			for (int e = first; e < last; ++e) {
				seen[s.events[e]] += 1;
				total[s.events[e]] += 1;
			}
			for (int k = 0; k < 4; ++k) {
				cr_assert_geq(seen[k], 1, "kind %d missing in substep %d of %d", k, sub, substeps);
			}
			/* The substep ends with every kind once, in order: ..., stretch, shear, bend, collision. */
			cr_assert_eq(s.events[last - 1], 3);
			cr_assert_eq(s.events[last - 2], 2);
			cr_assert_eq(s.events[last - 3], 1);
			cr_assert_eq(s.events[last - 4], 0);
		}
		for (int k = 0; k < 4; ++k) {
			int expected = kinds[k].importance > substeps ? kinds[k].importance : substeps;
			cr_assert_eq(total[k], expected, "kind %d over %d substeps", k, substeps);
		}
		plait_schedule_destroy(&s, &heap);
	}
}

Test(schedule, iterations_are_spread_evenly)
{
	/* 20 over 3 substeps: 6, 7, 7 (floor rounding of frame positions); never differing by more than one. */
	int n[3];
	for (int sub = 0; sub < 3; ++sub) {
		n[sub] = plait_schedule_substep_iterations(20, 3, sub);
	}
	cr_assert_eq(n[0] + n[1] + n[2], 20);
	for (int sub = 0; sub < 3; ++sub) {
		cr_assert(n[sub] == 6 || n[sub] == 7);
	}
	/* Fewer than substeps: once per substep. */
	cr_assert_eq(plait_schedule_substep_iterations(1, 5, 2), 1);
}

Test(schedule, collisions_lower_than_substeps_have_no_effect)
{
	plait_schedule a = build(6, 20, 2), b = build(6, 20, 6);
	cr_assert_eq(a.event_count, b.event_count);
	cr_assert_eq(memcmp(a.events, b.events, sizeof(int) * (size_t)a.event_count), 0);
	plait_schedule_destroy(&a, &heap);
	plait_schedule_destroy(&b, &heap);
}
