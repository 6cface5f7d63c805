/* A pair's state over a substep, carried from one list to the next.
 *
 * A pair keeps what friction and restitution need over its substep: the sums of its pushes and
 * of the tangential motion its friction took off (push_sum, rubbed: Coulomb's law over the
 * substep, mesh_contact.c), whether it pushed and how fast it closed (pushed, approach: bounce
 * at the substep's end), and whether it pushed or rested at the last collision iteration
 * (pushed_last: the contact passes that follow project it). A list is gathered again or mended
 * at a collision iteration, after the substep's contact passes have projected the old list, or
 * in the failsafe at the substep's end. Listed anew, a pair began the substep's sums again from
 * the collision iteration's push alone: friction's limit fell short of what the contact passes
 * had pushed, and a sheet lying on a sheet on a slope just under its friction angle slipped at
 * each gather (11.6 mm in 2 s at 30 degrees, friction 0.6; 1.0 mm carried).
 *
 * So the pairs of the old list with such state are kept aside before the listing, chained by
 * their first vertex, and a pair listed that matches one (type and vertices) takes its state.
 * Matching is exact and the same for any number of workers (the old list and each new pair
 * decide it), so results stay deterministic. */
#include "dynamics/mesh_contact_internal.h"

bool plait_mesh_contacts_has_state(const plait_mesh_contacts *mc, const contact_pair *pair)
{
	/* Friction takes off nothing without a push (rub), so sums without one are zero. */
	return pair->pushed_last || pair->pushed ||
	       (pair->sums_substep == (uint8_t)mc->substep_serial && pair->push_sum > 0.0f);
}

void plait_mesh_contacts_carry(plait_sim *sim, plait_mesh_contacts *mc, const contact_pair *pair)
{
	if (mc->carry_head == NULL) {
		return; /* no particles reserved: nothing listed */
	}
	if (mc->carried_count == mc->carried_capacity) {
		int bigger = mc->carried_capacity < 256 ? 256 : 2 * mc->carried_capacity;
		contact_pair *pairs =
		    plait_alloc_grow(&sim->allocator, mc->carried, sizeof *pairs, mc->carried_count, bigger);
		if (pairs == NULL) {
			return;
		}
		mc->carried = pairs;
		int *next =
		    plait_alloc_grow(&sim->allocator, mc->carried_next, sizeof *next, mc->carried_count, bigger);
		if (next == NULL) {
			/* The pairs grew and the chains did not: keep the old capacity for both. */
			return;
		}
		mc->carried_next = next;
		mc->carried_capacity = bigger;
	}
	int k = mc->carried_count++;
	mc->carried[k] = *pair;
	mc->carried_next[k] = mc->carry_head[pair->v[0]];
	mc->carry_head[pair->v[0]] = k;
}

void plait_mesh_contacts_take_carried(const plait_mesh_contacts *mc, contact_pair *pair)
{
	if (mc->carried_count == 0) {
		return;
	}
	for (int k = mc->carry_head[pair->v[0]]; k >= 0; k = mc->carried_next[k]) {
		const contact_pair *old = &mc->carried[k];
		if (old->type == pair->type && old->v[1] == pair->v[1] && old->v[2] == pair->v[2] &&
		    old->v[3] == pair->v[3]) {
			pair->pushed = old->pushed;
			pair->pushed_last = old->pushed_last;
			pair->sums_substep = old->sums_substep;
			pair->approach = old->approach;
			pair->push_sum = old->push_sum;
			pair->rubbed = old->rubbed;
			return;
		}
	}
}

void plait_mesh_contacts_drop_carried(plait_mesh_contacts *mc)
{
	for (int k = 0; k < mc->carried_count; ++k) {
		mc->carry_head[mc->carried[k].v[0]] = -1;
	}
	mc->carried_count = 0;
}

void plait_mesh_contacts_free_carried(plait_mesh_contacts *mc, const plait_allocator *a)
{
	plait_free(a, mc->carried);
	plait_free(a, mc->carried_next);
	mc->carried = NULL;
	mc->carried_next = NULL;
	mc->carried_count = 0;
	mc->carried_capacity = 0;
}
