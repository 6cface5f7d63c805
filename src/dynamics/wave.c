#include "dynamics/wave.h"

#include "dynamics/colouring.h"

bool plait_wave_takes(const plait_distance_block *block, int regions, int particle_count)
{
	const plait_colouring *colouring = &block->colouring;
	return block->compliant_count == 0 && colouring->boundary_cut_start != NULL &&
	       colouring->region_count == regions && colouring->particle_count == particle_count &&
	       plait_colouring_end(colouring) == block->count;
}

/* Slot o at region q (wave.h, "The order"). */
static void run_item(plait_wave *wave, int o, int q)
{
	const plait_wave_slot *slot = &wave->slots[o];
	plait_distance_block *block = slot->block;
	float ih2 = wave->inverse_h_squared;
	if (block == NULL) {
		int begin = plait_region_first(q, wave->regions, wave->particle_count),
		    end = plait_region_first(q + 1, wave->regions, wave->particle_count);
		wave->close(wave->context, slot->substep, begin, end);
		if (o == wave->slot_count - 1) {
			wave->leave(wave->context, begin, end);
		}
		return;
	}
	if (slot->sweep != PLAIT_SWEEP_FORWARD && q + 1 < wave->regions) {
		plait_distance_sweep_cut(block, wave->columns, q, ih2, slot->sweep == PLAIT_SWEEP_BACKWARD);
	}
	plait_distance_sweep_region(block, wave->columns, q, ih2, slot->sweep);
	if (slot->sweep != PLAIT_SWEEP_BACKWARD && q > 0) {
		plait_distance_sweep_cut(block, wave->columns, q - 1, ih2, slot->sweep == PLAIT_SWEEP_SYMMETRIC);
	}
}

void plait_wave_run(plait_wave *wave)
{
	int regions = wave->regions, slots = wave->slot_count;
	for (int t = 0; t < regions + slots; ++t) {
		if (t < regions) {
			wave->enter(wave->context, plait_region_first(t, regions, wave->particle_count),
			            plait_region_first(t + 1, regions, wave->particle_count));
		}
		for (int o = 0; o < slots; ++o) {
			int q = t - 1 - o;
			if (q < 0) {
				break;
			}
			if (q < regions) {
				run_item(wave, o, q);
			}
		}
	}
}
