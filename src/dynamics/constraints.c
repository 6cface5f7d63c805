#include "dynamics/constraints.h"

#include "dynamics/bend_kernel.h"
#include "dynamics/colouring.h"
#include "dynamics/distance_kernel.h"

/* Constraints per chunk of a parallel loop: large enough that claiming a chunk costs little
 * next to projecting it, small enough that a colour splits over the workers. A multiple of 16,
 * so chunks keep whole SIMD batches. */
#define DISTANCE_GRAIN 1024
#define BEND_GRAIN 256
#define LANES 8 /* hinges per bend batch (the compiler vectorises the lane loops) */

typedef struct distance_job {
	plait_distance_kernel *kernel;
	plait_distance_block *block;
	plait_point *points;
	const plait_columns *columns; /* non-NULL: the points are there (solver.c, "Columns") */
	float inverse_h_squared;
	plait_sweep sweep;
} distance_job;

/* Constraints [begin, end) of one run: they share no particle. */
static void distance_range(void *context, int begin, int end)
{
	distance_job *job = context;
	if (job->columns != NULL) {
		job->columns->project(job->block, job->columns, begin, end, job->inverse_h_squared);
		return;
	}
	job->kernel(job->block, job->points, begin, end, job->inverse_h_squared);
}

/* Regions [first, last), each swept run after run on one thread: forward, backward, or
 * (symmetric) forward and straight back while it is in cache. */
static void distance_regions(void *context, int first, int last)
{
	distance_job *job = context;
	const plait_colouring *colouring = &job->block->colouring;
	for (int r = first; r < last; ++r) {
		int run_first = colouring->region_start[r], run_last = colouring->region_start[r + 1];
		if (job->sweep != PLAIT_SWEEP_BACKWARD) {
			for (int k = run_first; k < run_last; ++k) {
				distance_range(job, colouring->run_start[k], colouring->run_start[k + 1]);
			}
		}
		if (job->sweep != PLAIT_SWEEP_FORWARD) {
			for (int k = run_last - 1; k >= run_first; --k) {
				distance_range(job, colouring->run_start[k], colouring->run_start[k + 1]);
			}
		}
	}
}

/* The boundary's runs one after another (each split over the workers), then what is not
 * coloured yet one by one; backward the other way. */
static void sweep_boundary(plait_parallel *parallel, distance_job *job, bool backward)
{
	plait_distance_block *block = job->block;
	const plait_colouring *colouring = &block->colouring;
	int coloured = plait_colouring_end(colouring);
	int boundary_first = colouring->run_count > 0 ? colouring->region_start[colouring->region_count] : 0;
	int runs = colouring->run_count - boundary_first, loose = block->count - coloured;
	for (int m = 0; !backward && m < runs; ++m) {
		int k = boundary_first + m;
		plait_parallel_for(parallel, distance_range, job, colouring->run_start[k],
		                   colouring->run_start[k + 1], DISTANCE_GRAIN);
	}
	for (int m = 0; m < loose; ++m) {
		int c = backward ? block->count - 1 - m : coloured + m;
		if (job->columns != NULL) {
			distance_range(job, c, c + 1);
		} else {
			plait_project_distance_scalar(block, job->points, c, c + 1, job->inverse_h_squared);
		}
	}
	for (int m = 0; backward && m < runs; ++m) {
		int k = colouring->run_count - 1 - m;
		plait_parallel_for(parallel, distance_range, job, colouring->run_start[k],
		                   colouring->run_start[k + 1], DISTANCE_GRAIN);
	}
}

/* A forward sweep goes through the regions side by side, then the boundary; a backward one the
 * other way. A symmetric sweep does the same projections as a forward sweep then a backward
 * one, ordered so that each region is swept back right after it was swept forward, while its
 * constraints and points are in cache (at hang-512, whose blocks overflow the last-level cache,
 * that was 12% of the frame): the boundary forward, every region there and back, the boundary
 * backward. The order stays a palindrome, so the sweep stays symmetric (architecture.md,
 * "Symmetric sweeps"). */
void plait_solve_distance(plait_distance_block *block, plait_particles *particles,
                          const plait_columns *columns, float inverse_h_squared, plait_sweep sweep,
                          plait_distance_kernel *kernel, plait_parallel *parallel)
{
	distance_job job = {kernel, block, particles->point, columns, inverse_h_squared, sweep};
	const plait_colouring *colouring = &block->colouring;
	if (sweep != PLAIT_SWEEP_FORWARD) {
		/* Backward, or the symmetric sweep's first half. */
		sweep_boundary(parallel, &job, sweep == PLAIT_SWEEP_BACKWARD);
	}
	plait_parallel_for(parallel, distance_regions, &job, 0, colouring->region_count, 1);
	if (sweep != PLAIT_SWEEP_BACKWARD) {
		sweep_boundary(parallel, &job, sweep == PLAIT_SWEEP_SYMMETRIC);
	}
}

void plait_distance_sweep_region(plait_distance_block *block, const plait_columns *columns, int region,
                                 float inverse_h_squared, plait_sweep sweep)
{
	distance_job job = {NULL, block, NULL, columns, inverse_h_squared, sweep};
	distance_regions(&job, region, region + 1);
}

void plait_distance_sweep_cut(plait_distance_block *block, const plait_columns *columns, int cut,
                              float inverse_h_squared, bool backward)
{
	distance_job job = {NULL, block, NULL, columns, inverse_h_squared, PLAIT_SWEEP_FORWARD};
	const plait_colouring *colouring = &block->colouring;
	int regions = colouring->region_count, runs = colouring->run_count - colouring->region_start[regions];
	for (int m = 0; m < runs; ++m) {
		const int *cut_start =
		    colouring->boundary_cut_start + (size_t)(backward ? runs - 1 - m : m) * (size_t)regions;
		if (cut_start[cut] < cut_start[cut + 1]) {
			distance_range(&job, cut_start[cut], cut_start[cut + 1]);
		}
	}
}

/* With e = p1 - p0, nA = e x (p2 - p0) and nB = (p0 - p1) x (p3 - p1) (the normals of the
 * triangles (p0,p1,p2) and (p1,p0,p3), equal when flat and consistently oriented), the angle
 * is atan2((nA x nB).e, nA.nB): the rotation about e taking nA to nB. Turning a wing about
 * the hinge by phi moves it by phi times its height h, so the wing gradients are
 * -n/h = -n |e| / |n|^2, and translation and rotation invariance give the hinge gradients as
 * the wings' gradients weighted by where each wing projects onto the edge. */
bool plait_dihedral_angle(vec3 p0, vec3 p1, vec3 p2, vec3 p3, float *angle, vec3 gradient[4])
{
	vec3 e = v3_sub(p1, p0);
	vec3 nA = v3_cross(e, v3_sub(p2, p0));
	vec3 nB = v3_cross(v3_sub(p0, p1), v3_sub(p3, p1));
	float e_length_sq = v3_length_sq(e);
	float nA_sq = v3_length_sq(nA), nB_sq = v3_length_sq(nB);
	if (e_length_sq < 1e-24f || nA_sq < 1e-30f || nB_sq < 1e-30f) {
		return false;
	}
	float e_length = sqrtf(e_length_sq);
	float sine = v3_dot(v3_cross(nA, nB), e) / e_length;
	float cosine = v3_dot(nA, nB);
	*angle = plait_atan2f(sine, cosine);
	if (gradient != NULL) {
		vec3 g2 = v3_scale(nA, -e_length / nA_sq);
		vec3 g3 = v3_scale(nB, -e_length / nB_sq);
		float a2 = v3_dot(v3_sub(p2, p0), e) / e_length_sq;
		float a3 = v3_dot(v3_sub(p3, p0), e) / e_length_sq;
		gradient[0] = v3_add(v3_scale(g2, a2 - 1.0f), v3_scale(g3, a3 - 1.0f));
		gradient[1] = v3_add(v3_scale(g2, -a2), v3_scale(g3, -a3));
		gradient[2] = g2;
		gradient[3] = g3;
	}
	return true;
}

/* The bend projection of one batch of at most LANES hinges sharing no particle, in the same
 * lane-array form as the distance batches (SIMD, results equal to sequential projection). The
 * math is plait_dihedral_angle's, written branch-free: a degenerate hinge (a zero-area
 * triangle or zero-length edge) gets a zero correction. */
static void project_bend_batch(plait_bend_block *block, plait_point *points, int first, int n,
                               float inverse_h_squared)
{
	float px[4][LANES], py[4][LANES], pz[4][LANES], wq[4][LANES];
	float rest[LANES], compliance[LANES], lambda[LANES];
	float gx[4][LANES], gy[4][LANES], gz[4][LANES], step[LANES];
	for (int lane = 0; lane < LANES; ++lane) {
		int c = first + (lane < n ? lane : 0);
		for (int k = 0; k < 4; ++k) {
			float w;
			plait_load_point(&points[block->quad[c][k]], &px[k][lane], &py[k][lane], &pz[k][lane], &w);
			wq[k][lane] = lane < n ? w : 0.0f;
		}
		rest[lane] = block->rest_angle[c];
		compliance[lane] = block->compliance[c];
		lambda[lane] = block->lambda[c];
	}
	for (int lane = 0; lane < LANES; ++lane) {
		float ex = px[1][lane] - px[0][lane], ey = py[1][lane] - py[0][lane], ez = pz[1][lane] - pz[0][lane];
		float ax = px[2][lane] - px[0][lane], ay = py[2][lane] - py[0][lane], az = pz[2][lane] - pz[0][lane];
		float bx = px[3][lane] - px[1][lane], by = py[3][lane] - py[1][lane], bz = pz[3][lane] - pz[1][lane];
		/* nA = e x (p2 - p0), nB = (p0 - p1) x (p3 - p1) = -e x (p3 - p1) */
		float nax = ey * az - ez * ay, nay = ez * ax - ex * az, naz = ex * ay - ey * ax;
		float nbx = -(ey * bz - ez * by), nby = -(ez * bx - ex * bz), nbz = -(ex * by - ey * bx);
		float e2 = ex * ex + ey * ey + ez * ez;
		float na2 = nax * nax + nay * nay + naz * naz, nb2 = nbx * nbx + nby * nby + nbz * nbz;
		int valid = (e2 > 1e-24f) & (na2 > 1e-30f) & (nb2 > 1e-30f);
		e2 = valid ? e2 : 1.0f;
		na2 = valid ? na2 : 1.0f;
		nb2 = valid ? nb2 : 1.0f;
		float el = sqrtf(e2);
		float cx = nay * nbz - naz * nby, cy = naz * nbx - nax * nbz, cz = nax * nby - nay * nbx;
		float sine = (cx * ex + cy * ey + cz * ez) / el;
		float cosine = nax * nbx + nay * nby + naz * nbz;
		float C = plait_atan2f(sine, cosine) - rest[lane];
		C = C > PLAIT_PI ? C - 2.0f * PLAIT_PI : C;
		C = C < -PLAIT_PI ? C + 2.0f * PLAIT_PI : C;
		float fa = -el / na2, fb = -el / nb2;
		float g2x = nax * fa, g2y = nay * fa, g2z = naz * fa;
		float g3x = nbx * fb, g3y = nby * fb, g3z = nbz * fb;
		float a2 = (ax * ex + ay * ey + az * ez) / e2;
		float dx3 = px[3][lane] - px[0][lane], dy3 = py[3][lane] - py[0][lane],
		      dz3 = pz[3][lane] - pz[0][lane];
		float a3 = (dx3 * ex + dy3 * ey + dz3 * ez) / e2;
		gx[0][lane] = g2x * (a2 - 1.0f) + g3x * (a3 - 1.0f);
		gy[0][lane] = g2y * (a2 - 1.0f) + g3y * (a3 - 1.0f);
		gz[0][lane] = g2z * (a2 - 1.0f) + g3z * (a3 - 1.0f);
		gx[1][lane] = g2x * -a2 + g3x * -a3;
		gy[1][lane] = g2y * -a2 + g3y * -a3;
		gz[1][lane] = g2z * -a2 + g3z * -a3;
		gx[2][lane] = g2x;
		gy[2][lane] = g2y;
		gz[2][lane] = g2z;
		gx[3][lane] = g3x;
		gy[3][lane] = g3y;
		gz[3][lane] = g3z;
		float denominator = 0.0f;
		for (int k = 0; k < 4; ++k) {
			denominator += wq[k][lane] * (gx[k][lane] * gx[k][lane] + gy[k][lane] * gy[k][lane] +
			                              gz[k][lane] * gz[k][lane]);
		}
		float alpha_tilde = compliance[lane] * inverse_h_squared;
		denominator += alpha_tilde;
		int active = valid & (denominator > 1e-30f);
		denominator = active ? denominator : 1.0f;
		float dlambda = (float)active * (-C - alpha_tilde * lambda[lane]) / denominator;
		lambda[lane] += dlambda;
		step[lane] = dlambda;
	}
	for (int lane = 0; lane < LANES; ++lane) {
		for (int k = 0; k < 4; ++k) {
			float s = wq[k][lane] * step[lane];
			px[k][lane] += s * gx[k][lane];
			py[k][lane] += s * gy[k][lane];
			pz[k][lane] += s * gz[k][lane];
		}
	}
	for (int lane = 0; lane < n; ++lane) {
		int c = first + lane;
		block->lambda[c] = lambda[lane];
		for (int k = 0; k < 4; ++k) {
			plait_store_point(&points[block->quad[c][k]], px[k][lane], py[k][lane], pz[k][lane], wq[k][lane]);
		}
	}
}

static void project_bend(plait_bend_block *block, plait_point *points, int c, float inverse_h_squared)
{
	const int *q = block->quad[c];
	float wq[4] = {points[q[0]].w, points[q[1]].w, points[q[2]].w, points[q[3]].w};
	if (wq[0] + wq[1] + wq[2] + wq[3] == 0.0f) {
		return;
	}
	float angle;
	vec3 g[4];
	if (!plait_dihedral_angle(points[q[0]].x, points[q[1]].x, points[q[2]].x, points[q[3]].x, &angle, g)) {
		return;
	}
	float C = angle - block->rest_angle[c];
	/* The shortest way round: a fold through +-pi must not unwind the long way. */
	C = C > PLAIT_PI ? C - 2.0f * PLAIT_PI : C;
	C = C < -PLAIT_PI ? C + 2.0f * PLAIT_PI : C;
	float denominator = 0.0f;
	for (int k = 0; k < 4; ++k) {
		denominator += wq[k] * v3_length_sq(g[k]);
	}
	float alpha_tilde = block->compliance[c] * inverse_h_squared;
	denominator += alpha_tilde;
	if (denominator < 1e-30f) {
		return;
	}
	float dlambda = (-C - alpha_tilde * block->lambda[c]) / denominator;
	block->lambda[c] += dlambda;
	for (int k = 0; k < 4; ++k) {
		points[q[k]].x = v3_mul_add(points[q[k]].x, wq[k] * dlambda, g[k]);
	}
}

void plait_project_bend_portable(plait_bend_block *block, plait_point *points, int begin, int end,
                                 float inverse_h_squared)
{
	for (int first = begin; first < end; first += LANES) {
		int n = end - first < LANES ? end - first : LANES;
		project_bend_batch(block, points, first, n, inverse_h_squared);
	}
}

plait_bend_kernel *plait_bend_kernel_for(plait_simd level)
{
#if PLAIT_X86_KERNELS
	if (level == PLAIT_SIMD_AVX2 || level == PLAIT_SIMD_AVX512) {
		return plait_project_bend_avx2;
	}
#endif
	(void)level;
	return plait_project_bend_portable;
}

typedef struct bend_job {
	plait_bend_kernel *kernel;
	plait_bend_block *block;
	plait_point *points;
	float inverse_h_squared;
} bend_job;

static void bend_range(void *context, int begin, int end)
{
	bend_job *job = context;
	job->kernel(job->block, job->points, begin, end, job->inverse_h_squared);
}

static void bend_regions(void *context, int first, int last)
{
	bend_job *job = context;
	const plait_colouring *colouring = &job->block->colouring;
	for (int k = colouring->region_start[first]; k < colouring->region_start[last]; ++k) {
		bend_range(job, colouring->run_start[k], colouring->run_start[k + 1]);
	}
}

/* Forward only, in the order of a forward distance sweep. */
void plait_solve_bend(plait_bend_block *block, plait_particles *particles, float inverse_h_squared,
                      plait_bend_kernel *kernel, plait_parallel *parallel)
{
	bend_job job = {kernel, block, particles->point, inverse_h_squared};
	const plait_colouring *colouring = &block->colouring;
	plait_parallel_for(parallel, bend_regions, &job, 0, colouring->region_count, 1);
	int boundary_first = colouring->run_count > 0 ? colouring->region_start[colouring->region_count] : 0;
	for (int k = boundary_first; k < colouring->run_count; ++k) {
		plait_parallel_for(parallel, bend_range, &job, colouring->run_start[k], colouring->run_start[k + 1],
		                   BEND_GRAIN);
	}
	for (int c = plait_colouring_end(colouring); c < block->count; ++c) {
		project_bend(block, particles->point, c, inverse_h_squared);
	}
}

void plait_solve_rod_bend(plait_rod_bend_block *block, plait_particles *particles, float inverse_h_squared)
{
	plait_point *points = particles->point;
	for (int c = 0; c < block->count; ++c) {
		plait_point *p0 = &points[block->triple[c][0]], *p1 = &points[block->triple[c][1]];
		plait_point *p2 = &points[block->triple[c][2]];
		float w0 = p0->w, w1 = p1->w, w2 = p2->w;
		float denominator = 0.25f * w0 + w1 + 0.25f * w2;
		if (denominator == 0.0f) {
			continue;
		}
		vec3 offset = v3_sub(p1->x, v3_scale(v3_add(p0->x, p2->x), 0.5f));
		float length = v3_length(offset);
		if (length < 1e-12f) {
			continue;
		}
		float C = length - block->rest[c];
		float alpha_tilde = block->compliance[c] * inverse_h_squared;
		float dlambda = (-C - alpha_tilde * block->lambda[c]) / (denominator + alpha_tilde);
		block->lambda[c] += dlambda;
		vec3 n = v3_scale(offset, dlambda / length);
		p0->x = v3_mul_add(p0->x, -0.5f * w0, n);
		p1->x = v3_mul_add(p1->x, w1, n);
		p2->x = v3_mul_add(p2->x, -0.5f * w2, n);
	}
}

float plait_distance_max_strain(const plait_distance_block *block, const plait_particles *particles)
{
	float worst = 0.0f;
	for (int c = 0; c < block->count; ++c) {
		float rest = block->rest[c];
		if (rest <= 0.0f) {
			continue;
		}
		float length =
		    v3_length(v3_sub(particles->point[block->pair[c][1]].x, particles->point[block->pair[c][0]].x));
		float strain = fabsf(length / rest - 1.0f);
		worst = strain > worst ? strain : worst;
	}
	return worst;
}
