/* The sweep order of constraint blocks: regions swept side by side, runs of independent
 * constraints inside them.
 *
 * Gauss-Seidel projects constraints one after another, and the order matters: a sweep in the
 * order the mesh was built (row after row) carries a correction along a whole column of a
 * hanging sheet in one pass, while a sweep colour after colour (the usual way to vectorise and
 * thread it) carries it one or two edges, and the sheet converges several times slower.
 *
 * So the order is kept, nearly. Particles are cut into regions by index (for a mesh, bands of
 * rows); a constraint whose particles are all in one region belongs to it, the others to the
 * boundary. Regions share no particle, so they are swept at the same time, one thread each,
 * each in its own order; then the boundary is swept. Inside a region, constraints are cut in
 * their order into slabs of PLAIT_SLAB_SIZE (more where the regions, capped at
 * PLAIT_MAX_REGIONS, hold more than PLAIT_REGION_SIZE: the same share of a region) and each
 * slab is coloured: a colour of a slab is a run of constraints that share no particle,
 * projected together in SIMD lanes. (Slabs of 512 in the 8,000-constraint regions of a
 * 512 x 512 cloth made it 7% slower, with no better strain.)
 *
 * Bands. Where every boundary constraint joins two adjacent regions (cut c lies between regions
 * c and c + 1), each boundary run is sorted by cut (boundary_cut_start): its constraints share no
 * particle, so the order changes nothing. A pass can then sweep the boundary cut by cut, each cut
 * next to its two regions, and where no particle is held by constraints of two cuts
 * (plait_sim.bands_agree, over all the blocks) passes can follow each other down the regions as a
 * wave (dynamics/wave.h).
 *
 * How the block is cut depends on the block alone, never on the thread count or the instruction
 * set, and constraints of a run or of different regions commute: the output is bit-identical
 * for any number of threads and any SIMD width. */
#ifndef PLAIT_DYNAMICS_COLOURING_H
#define PLAIT_DYNAMICS_COLOURING_H

#include <stdint.h>

#include "core/alloc.h"
#include "dynamics/sim.h"

#define PLAIT_SLAB_SIZE 512
#define PLAIT_MAX_COLOURS 64
#define PLAIT_REGION_SIZE 2048 /* constraints per region, about */
#define PLAIT_MAX_REGIONS 64

/* vertices holds count tuples of `arity` particle indices in [0, particle_count). Writes
 * order[k] = the constraint to put at position k and the runs and regions into *colouring (its
 * arrays allocated here). Greedy first fit in each slab: a constraint takes the lowest colour
 * none of its particles has yet in that slab; one that finds none of PLAIT_MAX_COLOURS free
 * becomes a run of its own. Returns false when out of memory, leaving *colouring empty. */
bool plait_colour_constraints(const plait_allocator *allocator, const int *vertices, int arity, int count,
                              int particle_count, int *order, plait_colouring *colouring);

/* Colours the constraint blocks of a sim that changed since they were last coloured
 * (sim->colouring_dirty), permuting their arrays. Nothing is changed when out of memory. */
bool plait_sim_colour(plait_sim *sim);

/* Forgets a block's runs: its constraints are then projected one by one. */
void plait_colouring_clear(plait_colouring *colouring, const plait_allocator *allocator);

/* The first particle of region r of `regions` cut for `particle_count` particles (the least i
 * with i * regions / particle_count >= r). */
static inline int plait_region_first(int r, int regions, int particle_count)
{
	return (int)(((int64_t)r * particle_count + regions - 1) / regions);
}

/* End of the coloured constraints (the start of those projected one by one). */
static inline int plait_colouring_end(const plait_colouring *colouring)
{
	return colouring->run_count > 0 ? colouring->run_start[colouring->run_count] : 0;
}

#endif
