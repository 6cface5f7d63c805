#include "dynamics/constraints.h"

/* One projection of distance constraint c (see the header for the update). */
static inline void project_distance(plait_distance_block *block, vec3 *x, const float *w, int c,
                                    float inverse_h_squared)
{
	int i = block->pair[c][0], j = block->pair[c][1];
	float w_sum = w[i] + w[j];
	if (w_sum == 0.0f) {
		return;
	}
	vec3 d = v3_sub(x[j], x[i]);
	float length = sqrtf(d.x * d.x + d.y * d.y + d.z * d.z);
	length = length > 1e-12f ? length : 1e-12f;
	float C = length - block->rest[c];
	/* Branch-free choice of direction: the sign of C is unpredictable, and a negative
	 * compliance means "no resistance this way". */
	float alpha = C > 0.0f ? block->compliance_tension[c] : block->compliance_compression[c];
	float active = alpha >= 0.0f ? 1.0f : 0.0f;
	float alpha_tilde = plait_maxf(alpha, 0.0f) * inverse_h_squared;
	float denominator = (w_sum + alpha_tilde) * length;
	float dlambda_over_length = active * (-C - alpha_tilde * block->lambda[c]) / denominator;
	block->lambda[c] += dlambda_over_length * length;
	vec3 n = v3_scale(d, dlambda_over_length);
	x[i] = v3_mul_add(x[i], -w[i], n);
	x[j] = v3_mul_add(x[j], w[j], n);
}

#define LANES 8

/* Projects one batch of at most LANES constraints that share no particle. Positions are
 * gathered once into lane arrays, the arithmetic runs over whole lanes (the compiler turns it
 * into SIMD), and the new positions are stored back without reading them again. Since the
 * constraints are independent, the result is exactly that of projecting them one after
 * another. Lanes past n carry zero inverse masses and change nothing; the block's arrays are
 * padded by LANES entries so their parameters can be read whole. */
static void project_distance_batch(plait_distance_block *block, vec3 *x, const float *w, int first, int n,
                                   float inverse_h_squared)
{
	float xi[LANES], yi[LANES], zi[LANES], xj[LANES], yj[LANES], zj[LANES], wi[LANES], wj[LANES];
	const int(*pair)[2] = (const int(*)[2])block->pair + first;
	for (int lane = 0; lane < LANES; ++lane) {
		int i = pair[lane][0], j = pair[lane][1]; /* padding keeps lanes past n readable */
		xi[lane] = x[i].x;
		yi[lane] = x[i].y;
		zi[lane] = x[i].z;
		xj[lane] = x[j].x;
		yj[lane] = x[j].y;
		zj[lane] = x[j].z;
		wi[lane] = lane < n ? w[i] : 0.0f;
		wj[lane] = lane < n ? w[j] : 0.0f;
	}
	const float *rest = block->rest + first, *tension = block->compliance_tension + first;
	const float *compression = block->compliance_compression + first;
	float *lambda = block->lambda + first;
	float lambda_out[LANES];
	for (int lane = 0; lane < LANES; ++lane) {
		float dx = xj[lane] - xi[lane], dy = yj[lane] - yi[lane], dz = zj[lane] - zi[lane];
		float w_sum = wi[lane] + wj[lane];
		float length = sqrtf(dx * dx + dy * dy + dz * dz);
		length = length > 1e-12f ? length : 1e-12f;
		float C = length - rest[lane];
		/* Branch-free: the sign of C is unpredictable, and a negative compliance means "no
		 * resistance this way". */
		float tension_alpha = tension[lane], compression_alpha = compression[lane], lambda_in = lambda[lane];
		float alpha = C > 0.0f ? tension_alpha : compression_alpha;
		float active = (float)((alpha >= 0.0f) & (w_sum > 0.0f));
		float alpha_tilde = (alpha > 0.0f ? alpha : 0.0f) * inverse_h_squared;
		float denominator = (w_sum + alpha_tilde) * length;
		denominator = w_sum > 0.0f ? denominator : 1.0f;
		float s = active * (-C - alpha_tilde * lambda_in) / denominator;
		lambda_out[lane] = lambda_in + s * length;
		float si = wi[lane] * s, sj = wj[lane] * s;
		xi[lane] -= si * dx;
		yi[lane] -= si * dy;
		zi[lane] -= si * dz;
		xj[lane] += sj * dx;
		yj[lane] += sj * dy;
		zj[lane] += sj * dz;
	}
	for (int lane = 0; lane < n; ++lane) {
		int i = pair[lane][0], j = pair[lane][1];
		lambda[lane] = lambda_out[lane];
		x[i] = (vec3){xi[lane], yi[lane], zi[lane]};
		x[j] = (vec3){xj[lane], yj[lane], zj[lane]};
	}
}

void plait_solve_distance(plait_distance_block *block, plait_particles *particles, float inverse_h_squared,
                          plait_sweep sweep)
{
	vec3 *x = particles->x;
	const float *w = particles->w;
	int count = block->count;
	int batches = block->batch_count;
	int batched = batches > 0 ? block->batch_start[batches] : 0;
	if (sweep != PLAIT_SWEEP_BACKWARD) {
		for (int b = 0; b < batches; ++b) {
			int first = block->batch_start[b];
			project_distance_batch(block, x, w, first, block->batch_start[b + 1] - first, inverse_h_squared);
		}
		for (int c = batched; c < count; ++c) {
			project_distance(block, x, w, c, inverse_h_squared);
		}
	}
	if (sweep != PLAIT_SWEEP_FORWARD) {
		for (int c = count - 1; c >= batched; --c) {
			project_distance(block, x, w, c, inverse_h_squared);
		}
		for (int b = batches - 1; b >= 0; --b) {
			int first = block->batch_start[b];
			project_distance_batch(block, x, w, first, block->batch_start[b + 1] - first, inverse_h_squared);
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
static void project_bend_batch(plait_bend_block *block, vec3 *x, const float *w, int first, int n,
                               float inverse_h_squared)
{
	float px[4][LANES], py[4][LANES], pz[4][LANES], wq[4][LANES];
	float rest[LANES], compliance[LANES], lambda[LANES];
	float gx[4][LANES], gy[4][LANES], gz[4][LANES], step[LANES];
	for (int lane = 0; lane < LANES; ++lane) {
		int c = first + (lane < n ? lane : 0);
		for (int k = 0; k < 4; ++k) {
			int i = block->quad[c][k];
			px[k][lane] = x[i].x;
			py[k][lane] = x[i].y;
			pz[k][lane] = x[i].z;
			wq[k][lane] = lane < n ? w[i] : 0.0f;
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
			x[block->quad[c][k]] = (vec3){px[k][lane], py[k][lane], pz[k][lane]};
		}
	}
}

static void project_bend(plait_bend_block *block, vec3 *x, const float *w, int c, float inverse_h_squared)
{
	const int *q = block->quad[c];
	float wq[4] = {w[q[0]], w[q[1]], w[q[2]], w[q[3]]};
	if (wq[0] + wq[1] + wq[2] + wq[3] == 0.0f) {
		return;
	}
	float angle;
	vec3 g[4];
	if (!plait_dihedral_angle(x[q[0]], x[q[1]], x[q[2]], x[q[3]], &angle, g)) {
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
		x[q[k]] = v3_mul_add(x[q[k]], wq[k] * dlambda, g[k]);
	}
}

void plait_solve_bend(plait_bend_block *block, plait_particles *particles, float inverse_h_squared)
{
	vec3 *x = particles->x;
	const float *w = particles->w;
	int batches = block->batch_count;
	for (int b = 0; b < batches; ++b) {
		int first = block->batch_start[b];
		project_bend_batch(block, x, w, first, block->batch_start[b + 1] - first, inverse_h_squared);
	}
	for (int c = batches > 0 ? block->batch_start[batches] : 0; c < block->count; ++c) {
		project_bend(block, x, w, c, inverse_h_squared);
	}
}

void plait_solve_rod_bend(plait_rod_bend_block *block, plait_particles *particles, float inverse_h_squared)
{
	vec3 *x = particles->x;
	const float *w = particles->w;
	for (int c = 0; c < block->count; ++c) {
		int i0 = block->triple[c][0], i1 = block->triple[c][1], i2 = block->triple[c][2];
		float w0 = w[i0], w1 = w[i1], w2 = w[i2];
		float denominator = 0.25f * w0 + w1 + 0.25f * w2;
		if (denominator == 0.0f) {
			continue;
		}
		vec3 offset = v3_sub(x[i1], v3_scale(v3_add(x[i0], x[i2]), 0.5f));
		float length = v3_length(offset);
		if (length < 1e-12f) {
			continue;
		}
		float C = length - block->rest[c];
		float alpha_tilde = block->compliance[c] * inverse_h_squared;
		float dlambda = (-C - alpha_tilde * block->lambda[c]) / (denominator + alpha_tilde);
		block->lambda[c] += dlambda;
		vec3 n = v3_scale(offset, dlambda / length);
		x[i0] = v3_mul_add(x[i0], -0.5f * w0, n);
		x[i1] = v3_mul_add(x[i1], w1, n);
		x[i2] = v3_mul_add(x[i2], -0.5f * w2, n);
	}
}

void plait_solve_tethers(plait_tether_block *block, plait_particles *particles)
{
	vec3 *x = particles->x;
	const float *w = particles->w;
	for (int c = 0; c < block->count; ++c) {
		int i = block->pair[c][0], anchor = block->pair[c][1];
		float w_sum = w[i] + w[anchor];
		if (w_sum == 0.0f) {
			continue;
		}
		vec3 d = v3_sub(x[i], x[anchor]);
		float length = sqrtf(v3_length_sq(d));
		float excess = length - block->length[c];
		if (excess <= 0.0f) {
			continue;
		}
		vec3 correction = v3_scale(d, block->stiffness[c] * excess / (length * w_sum));
		x[i] = v3_mul_add(x[i], -w[i], correction);
		x[anchor] = v3_mul_add(x[anchor], w[anchor], correction);
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
		float length = v3_length(v3_sub(particles->x[block->pair[c][1]], particles->x[block->pair[c][0]]));
		float strain = fabsf(length / rest - 1.0f);
		worst = strain > worst ? strain : worst;
	}
	return worst;
}
