#include "dynamics/air.h"

#include <string.h>

bool plait_air_active(const plait_sim *sim)
{
	if (sim->settings.air_density <= 0.0f) {
		return false;
	}
	for (int m = 0; m < sim->material_count; ++m) {
		const plait_material *mat = &sim->materials[m];
		if (mat->drag > 0.0f || mat->tangential_drag > 0.0f || mat->lift > 0.0f || mat->point_drag > 0.0f) {
			return true;
		}
	}
	return false;
}

/* Integer hash to [-1, 1]: deterministic noise without global state. */
static float hash_to_unit(uint32_t a, uint32_t b, uint32_t c, uint32_t d, uint32_t e)
{
	uint32_t h = a * 0x9E3779B1u ^ b * 0x85EBCA77u ^ c * 0xC2B2AE3Du ^ d * 0x27D4EB2Fu ^ e * 0x165667B1u;
	h ^= h >> 15;
	h *= 0x2C1B3C6Du;
	h ^= h >> 12;
	h *= 0x297A2D39u;
	h ^= h >> 15;
	return (float)(h & 0xFFFFFFu) / (float)0x7FFFFF - 1.0f;
}

/* A cell coordinate for the noise; NaN and huge values share the outermost cells. */
static uint32_t noise_cell(float value)
{
	float c = floorf(value);
	if (!(c >= -1e9f)) {
		c = -1e9f;
	} else if (c > 1e9f) {
		c = 1e9f;
	}
	return (uint32_t)(int32_t)c;
}

static vec3 wind_noise(const plait_sim *sim, vec3 centroid, double time)
{
	const plait_settings *s = &sim->settings;
	float speed = v3_length(s->wind_velocity);
	if (s->wind_noise <= 0.0f || speed <= 0.0f) {
		return v3(0.0f, 0.0f, 0.0f);
	}
	float cell = 0.5f / s->space_scale;
	uint32_t cx = noise_cell(centroid.x / cell), cy = noise_cell(centroid.y / cell),
	         cz = noise_cell(centroid.z / cell);
	double slot = time / 0.25;
	uint32_t t0 = (uint32_t)(int64_t)floor(slot);
	float f = (float)(slot - floor(slot));
	vec3 a = {hash_to_unit(s->seed, cx, cy, cz, t0 * 3u), hash_to_unit(s->seed, cx, cy, cz, t0 * 3u + 1u),
	          hash_to_unit(s->seed, cx, cy, cz, t0 * 3u + 2u)};
	uint32_t t1 = t0 + 1u;
	vec3 b = {hash_to_unit(s->seed, cx, cy, cz, t1 * 3u), hash_to_unit(s->seed, cx, cy, cz, t1 * 3u + 1u),
	          hash_to_unit(s->seed, cx, cy, cz, t1 * 3u + 2u)};
	return v3_scale(v3_lerp(a, b, f), s->wind_noise * speed);
}

static void add_drag_tensor(float *k, vec3 n, float normal_coefficient, float tangential_coefficient)
{
	/* K = t I + (c - t) n n^T, stored xx, yy, zz, xy, xz, yz. */
	float d = normal_coefficient - tangential_coefficient;
	k[0] += tangential_coefficient + d * n.x * n.x;
	k[1] += tangential_coefficient + d * n.y * n.y;
	k[2] += tangential_coefficient + d * n.z * n.z;
	k[3] += d * n.x * n.y;
	k[4] += d * n.x * n.z;
	k[5] += d * n.y * n.z;
}

static vec3 drag_tensor_apply(const float *k, vec3 v)
{
	return v3(k[0] * v.x + k[3] * v.y + k[4] * v.z, k[3] * v.x + k[1] * v.y + k[5] * v.z,
	          k[4] * v.x + k[5] * v.y + k[2] * v.z);
}

void plait_air_accumulate(plait_sim *sim, double time)
{
	plait_particles *p = &sim->particles;
	const plait_settings *s = &sim->settings;
	if (p->count == 0) {
		return;
	}
	memset(p->drag_matrix, 0, sizeof(float) * 6 * (size_t)p->count);
	memset(p->air_force, 0, sizeof(vec3) * (size_t)p->count);
	memset(p->lift_force, 0, sizeof(vec3) * (size_t)p->count);
	float rho = s->air_density;
	float scale = s->space_scale;
	/* Force (scene units) per unit scene velocity for a coefficient c on area A (scene units):
	 * c rho A s^2; lift: c rho A |u|^2 s^3 (see the header). */
	float linear_factor = rho * scale * scale;
	float lift_factor = linear_factor * scale;

	for (int t = 0; t < sim->aero.count; ++t) {
		const plait_material *mat = &sim->materials[sim->aero.material[t]];
		if (mat->drag <= 0.0f && mat->tangential_drag <= 0.0f && mat->lift <= 0.0f) {
			continue;
		}
		const int *tri = sim->aero.triangle[t];
		vec3 a = p->point[tri[0]].x, b = p->point[tri[1]].x, c = p->point[tri[2]].x;
		vec3 normal = v3_cross(v3_sub(b, a), v3_sub(c, a));
		float twice_area = v3_length(normal);
		if (twice_area <= 0.0f) {
			continue;
		}
		vec3 n = v3_scale(normal, 1.0f / twice_area);
		/* The weights were set for the rest shape; scale them with the current area. */
		const float *weight = sim->aero.weight[t];
		float rest_area = weight[0] + weight[1] + weight[2];
		float area_scale = rest_area > 0.0f ? 0.5f * twice_area / rest_area : 0.0f;
		vec3 wind = s->wind_velocity;
		if (s->wind_noise > 0.0f) {
			vec3 centroid = v3_scale(v3_add(v3_add(a, b), c), 1.0f / 3.0f);
			wind = v3_add(wind, wind_noise(sim, centroid, time));
		}
		float normal_coefficient = mat->drag * linear_factor * area_scale;
		float tangential_coefficient = mat->tangential_drag * linear_factor * area_scale;
		vec3 lift = v3(0.0f, 0.0f, 0.0f);
		if (mat->lift > 0.0f) {
			vec3 v_mean = v3_scale(v3_add(v3_add(p->v[tri[0]], p->v[tri[1]]), p->v[tri[2]]), 1.0f / 3.0f);
			vec3 u = v3_sub(wind, v_mean);
			float speed_sq = v3_length_sq(u);
			if (speed_sq > 1e-12f) {
				vec3 u_hat = v3_scale(u, 1.0f / sqrtf(speed_sq));
				float cosine = v3_dot(u_hat, n);
				vec3 across = v3_sub(n, v3_scale(u_hat, cosine));
				if (cosine < 0.0f) {
					across = v3_neg(across);
				}
				float sine = v3_length(across);
				if (sine > 1e-6f) {
					float magnitude = mat->lift * lift_factor * area_scale * speed_sq * fabsf(cosine) * sine;
					lift = v3_scale(across, magnitude / sine);
				}
			}
		}
		for (int k = 0; k < 3; ++k) {
			int i = tri[k];
			float *drag = p->drag_matrix + 6 * (size_t)i;
			float before[6];
			memcpy(before, drag, sizeof before);
			add_drag_tensor(drag, n, normal_coefficient * weight[k], tangential_coefficient * weight[k]);
			float delta[6];
			for (int e = 0; e < 6; ++e) {
				delta[e] = drag[e] - before[e];
			}
			p->air_force[i] = v3_add(p->air_force[i], drag_tensor_apply(delta, wind));
			p->lift_force[i] = v3_mul_add(p->lift_force[i], weight[k], lift);
		}
	}

	for (int i = 0; i < p->count; ++i) {
		const plait_material *mat = &sim->materials[p->material[i]];
		if (mat->point_drag <= 0.0f) {
			continue;
		}
		float coefficient = mat->point_drag * rho * mat->point_area; /* area already in m^2 */
		float *drag = p->drag_matrix + 6 * (size_t)i;
		drag[0] += coefficient;
		drag[1] += coefficient;
		drag[2] += coefficient;
		p->air_force[i] = v3_mul_add(p->air_force[i], coefficient, s->wind_velocity);
	}
}

/* Solves (m I + h K) v = rhs for symmetric positive K. */
static vec3 solve_implicit_drag(float mass, float h, const float *k, vec3 rhs)
{
	float a00 = mass + h * k[0], a11 = mass + h * k[1], a22 = mass + h * k[2];
	float a01 = h * k[3], a02 = h * k[4], a12 = h * k[5];
	float c00 = a11 * a22 - a12 * a12;
	float c01 = a02 * a12 - a01 * a22;
	float c02 = a01 * a12 - a02 * a11;
	float determinant = a00 * c00 + a01 * c01 + a02 * c02;
	if (!(fabsf(determinant) > 0.0f)) {
		return v3_scale(rhs, 1.0f / mass);
	}
	float c11 = a00 * a22 - a02 * a02;
	float c12 = a01 * a02 - a00 * a12;
	float c22 = a00 * a11 - a01 * a01;
	float inverse = 1.0f / determinant;
	return v3((c00 * rhs.x + c01 * rhs.y + c02 * rhs.z) * inverse,
	          (c01 * rhs.x + c11 * rhs.y + c12 * rhs.z) * inverse,
	          (c02 * rhs.x + c12 * rhs.y + c22 * rhs.z) * inverse);
}

void plait_integrate_velocities(plait_sim *sim, float h, bool air, int begin, int end)
{
	plait_particles *p = &sim->particles;
	vec3 gravity = sim->settings.gravity;
	for (int i = begin; i < end; ++i) {
		if (p->point[i].w == 0.0f) {
			continue;
		}
		vec3 v = p->v[i];
		if (air) {
			float mass = p->mass[i];
			const float *k = p->drag_matrix + 6 * (size_t)i;
			/* Lift grows with the square of the relative air speed while drag grows linearly, so
			 * an explicit lift can pump energy (seed 000 §5.3). One substep of lift may change
			 * the velocity by at most half the air speed relative to the vertex. */
			vec3 lift_change = v3_scale(p->lift_force[i], h / mass);
			float limit = 0.5f * v3_length(v3_sub(sim->settings.wind_velocity, v));
			float change = v3_length(lift_change);
			if (change > limit) {
				lift_change = v3_scale(lift_change, limit / change);
			}
			vec3 rhs = v3_add(v3_scale(v3_add(v, lift_change), mass),
			                  v3_scale(v3_add(v3_scale(gravity, mass), p->air_force[i]), h));
			v = solve_implicit_drag(mass, h, k, rhs);
		} else {
			v = v3_mul_add(v, h, gravity);
		}
		p->v[i] = plait_damp_velocity(v, sim->materials[p->material[i]].damp, h);
	}
}
