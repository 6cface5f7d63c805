/* The simulation state of one world: one particle store for every object (paper §4: the
 * dynamics of a simplicial complex is the motion of its vertices), constraint blocks that refer
 * to particles by world index (so a constraint can join two objects), colliders and settings.
 * The world layer (world/) owns a plait_sim and maps objects onto ranges of it. */
#ifndef PLAIT_DYNAMICS_SIM_H
#define PLAIT_DYNAMICS_SIM_H

#include <stdint.h>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "collision/shape.h"
#include "core/alloc.h"
#include "core/parallel.h"
#include "dynamics/schedule.h"

enum {
	PLAIT_PARTICLE_PINNED = 1,    /* kinematic: follows pin_start -> pin_end over the frame */
	PLAIT_PARTICLE_COLLIDE = 2,   /* takes part in collisions */
	PLAIT_PARTICLE_CONTACT = 4,   /* touched something in the current substep */
	PLAIT_PARTICLE_SUPPORTED = 8, /* rested on a plane collider in the previous substep */
	PLAIT_PARTICLE_ON_PLANE = 16, /* touched a plane collider in the current substep */
	PLAIT_PARTICLE_TOUCHED = 32,  /* touched a collider since the last contact pass's gathering */
};

/* Per-object attributes the solver needs per particle (indexed by particles.material). */
typedef struct plait_material {
	int object; /* owning object slot */
	plait_object_type type;
	float thickness; /* scene units */
	float friction;
	float stickiness;
	float bounce;
	float damp;                        /* 1/s */
	float damp_factor;                 /* exp(-damp h) for this frame's substep h; 1 without damp */
	float point_drag;                  /* curves and particles: drag coefficient of each vertex */
	float point_area;                  /* m^2: cross-section used with point_drag */
	float drag, tangential_drag, lift; /* cloth triangles */
	bool collide;
	bool retired;           /* its object destroyed: no particle refers to it any more */
	bool self_collide;      /* the object collides with itself */
	int self_flag;          /* cloth: plait_self_collision_flag */
	int collider_flag;      /* cloth: plait_collision_flag */
	float self_width_scale; /* cloth: self-collision thickness / thickness */
	int collision_layer;    /* see plait_surface_def */
} plait_material;
/* The particle passes gather damp_factor by material index times this size in floats. */
_Static_assert(sizeof(plait_material) % sizeof(float) == 0,
               "plait_material must be a whole number of floats");

/* A particle's position and inverse mass in one 16-byte record, so that a constraint kernel
 * fetches everything it needs about a vertex with one vector load (and stores it with one). */
typedef struct plait_point {
	vec3 x;  /* position, scene units */
	float w; /* inverse mass, 1/kg; 0 = pinned or kinematic */
} plait_point;

/* Particles a world can hold: point byte offsets (plait_distance_block.point_offset) must fit
 * 32 bits. */
#define PLAIT_MAX_PARTICLES ((int)(UINT32_MAX / sizeof(plait_point)))

static inline uint32_t plait_point_offset(int index)
{
	return (uint32_t)index * (uint32_t)sizeof(plait_point);
}

/* Points are read and written whole, 16 bytes at a time, by every kernel. A load that does not
 * match the store it depends on (a 4-byte load from the middle of a 16-byte store still in
 * flight, or a 16-byte load over several smaller stores) cannot take its data from the store
 * buffer and waits for the store to retire: the dihedral bend kernel, reading x, y and z one
 * by one just after the distance kernel wrote them whole, ran 2.1 times slower for the same
 * instructions. */
static inline void plait_load_point(const plait_point *point, float *x, float *y, float *z, float *w)
{
#if defined(__SSE2__)
	__m128 v = _mm_load_ps(&point->x.x);
	*x = _mm_cvtss_f32(v);
	*y = _mm_cvtss_f32(_mm_shuffle_ps(v, v, _MM_SHUFFLE(1, 1, 1, 1)));
	*z = _mm_cvtss_f32(_mm_movehl_ps(v, v));
	*w = _mm_cvtss_f32(_mm_shuffle_ps(v, v, _MM_SHUFFLE(3, 3, 3, 3)));
#else
	plait_point p = *point;
	*x = p.x.x;
	*y = p.x.y;
	*z = p.x.z;
	*w = p.w;
#endif
}

static inline void plait_store_point(plait_point *point, float x, float y, float z, float w)
{
#if defined(__SSE2__)
	_mm_store_ps(&point->x.x, _mm_setr_ps(x, y, z, w));
#else
	*point = (plait_point){{x, y, z}, w};
#endif
}

/* Structure of arrays: one entry per particle of every object. */
typedef struct plait_particles {
	int count, capacity;
	plait_point *point; /* position and inverse mass; 16-byte aligned */
	vec3 *x_prev;       /* position at the start of the current substep */
	vec3 *v;            /* velocity, scene units per second */
	float *mass;        /* kg, kept while pinned */
	float *radius;      /* collision radius, scene units */
	int *material;
	uint8_t *flags;
	vec3 *pin_start, *pin_end; /* pin targets at frame start and end */
	vec3 *x_start;             /* position when the particle was added (start-frame separations) */
	vec3 *contact_normal;      /* world normal of the last contact in this substep */
	vec3 *contact_velocity;    /* velocity of the touched surface */
	float *contact_bounce, *contact_stickiness;
	/* Collider pushes along their normals and the tangential motion their friction took off, each
	 * summed over the substep's collision iterations and contact passes (scene units; read only
	 * with PLAIT_PARTICLE_CONTACT set, which the substep's end clears). Friction acts on the whole
	 * substep's motion and may take off up to friction times all the pushes less what it took
	 * before: Coulomb's law over the substep, however many passes share it (contact.c). */
	float *contact_push, *contact_rub;
	float *drag_matrix;       /* 6 per particle: symmetric implicit air drag (kg/s) */
	vec3 *air_force;          /* explicit air force toward the wind (N in scene units) */
	vec3 *lift_force;         /* lift (N in scene units), limited when integrated */
	plait_point *point_frame; /* state at the start of the frame, restored if it fails */
	vec3 *v_frame;
} plait_particles;

/* The sweep order of a constraint block (dynamics/colouring.h). Constraints are stored region
 * by region, then the boundary's. Each is a list of runs of constraints that share no particle;
 * run k is [run_start[k], run_start[k + 1]). Region r owns runs [region_start[r],
 * region_start[r + 1]); the boundary owns runs [region_start[region_count], run_count).
 * Constraints from run_start[run_count] to the block's end (added since the block was last
 * coloured) are projected one by one, in order. */
typedef struct plait_colouring {
	int region_count, run_count;
	int *region_start; /* region_count + 1 entries */
	int *run_start;    /* run_count + 1 entries */
	/* Distance blocks: the layout of the SIMD batches from each coloured position
	 * (dynamics/batch_layout.h), or NULL: every batch gathered. */
	unsigned char *batch_layout;
	/* Distance blocks: the segments of the column kernel (dynamics/batch_layout.h), or NULL. */
	struct plait_segment *segments;
	int segment_count;
	/* The particle count the regions were cut for: region r holds the particles i with
	 * i * region_count / particle_count == r. */
	int particle_count;
	/* Distance blocks whose boundary is banded (colouring.h, "Bands"), or NULL: each boundary
	 * run's constraints sorted by cut, those of cut c (between regions c and c + 1) in run m being
	 * [boundary_cut_start[m * region_count + c], boundary_cut_start[m * region_count + c + 1]). */
	int *boundary_cut_start;
} plait_colouring;

/* The points as columns (plait_sim.column_x and the rest), for the column kernels
 * (distance_kernel.h), and the kernel that projects on them. */
struct plait_distance_block;
typedef struct plait_columns plait_columns;
typedef void plait_column_kernel(struct plait_distance_block *block, const plait_columns *columns, int begin,
                                 int end, float inverse_h_squared);
struct plait_columns {
	float *x, *y, *z, *w;
	plait_column_kernel *project;
};

/* Point i of the columns, and its position written back (w does not change in a frame). */
static inline plait_point plait_column_point(const plait_columns *columns, int i)
{
	return (plait_point){{columns->x[i], columns->y[i], columns->z[i]}, columns->w[i]};
}

static inline void plait_column_set(const plait_columns *columns, int i, vec3 x)
{
	columns->x[i] = x.x;
	columns->y[i] = x.y;
	columns->z[i] = x.z;
}

/* A level's column kernel and its copies of the points into columns and back (NULL: none). */
typedef struct plait_column_ops {
	plait_column_kernel *project;
	void (*to_columns)(const plait_point *points, const plait_columns *columns, int begin, int end);
	void (*from_columns)(plait_point *points, const plait_columns *columns, int begin, int end);
} plait_column_ops;

/* Distance constraints |x_j - x_i| = rest (stretch, compression and shear). Compliance per
 * direction: when longer than rest, compliance_tension; when shorter, compliance_compression;
 * a negative compliance (PLAIT_NO_RESISTANCE) means no resistance that way. */
#define PLAIT_NO_RESISTANCE (-1.0f)
typedef struct plait_distance_block {
	int count, capacity;
	int (*pair)[2];
	/* pair as byte offsets into the point array (index * sizeof(plait_point)): the vector
	 * kernels address points with them directly, without widening and scaling each index. */
	uint32_t (*point_offset)[2];
	float *rest;
	float *compliance_tension;
	float *compliance_compression;
	float *lambda;
	/* Constraints with a nonzero compliance either way. With none, the kernels take a path
	 * without compliances and multipliers (lambda stays zero and is not written). */
	int compliant_count;
	plait_colouring colouring;
} plait_distance_block;

/* Signed dihedral angle across an edge (p0, p1) between wings p2 and p3 (cloth bend). */
typedef struct plait_bend_block {
	int count, capacity;
	int (*quad)[4];
	float *rest_angle;
	float *compliance;
	float *lambda;
	plait_colouring colouring;
} plait_bend_block;

/* Curve bend: distance of p1 from the midpoint of p0 and p2 (zero for a straight rest). */
typedef struct plait_rod_bend_block {
	int count, capacity;
	int (*triple)[3];
	float *rest;
	float *compliance;
	float *lambda;
} plait_rod_bend_block;

/* Pins a free vertex is tethered to, at most (its nearest ones; world/tethers.c). */
#define PLAIT_TETHER_ANCHORS 4

/* Tethers: particle pair[c][0] stays within length[c] of its anchor pair[c][1]. A particle's
 * tethers are consecutive (a row of at most PLAIT_TETHER_ANCHORS). */
typedef struct plait_tether_block {
	int count, capacity;
	int (*pair)[2];
	float *length;
	/* Per tether, but the same for all of a cloth's (world/tethers.c): the solver takes a
	 * particle's tethers together with the first one's (tether.c). */
	float *stiffness;
	bool fixed_anchors; /* every anchor pinned: set at each frame's start (plait_sim_step) */
	bool still_anchors; /* and none moves in the frame (its point is its pin's start and end) */
	/* And no anchor coordinate is -0, the one value a distance projection changes on a pinned
	 * point (-0 - -0 is +0): each anchor's bits then hold through the frame (wave.h). */
	bool anchors_keep_bits;
	bool lanes_stale;                 /* pair[] changed since `lanes` was derived from it */
	struct plait_tether_lanes *lanes; /* the solver's regrouping (tether.c); NULL until derived */
} plait_tether_block;

/* Cloth triangles that feel the air. weight[k] is the area (scene units^2) the triangle lends
 * corner k, chosen so that every vertex's total matches the area its mass was computed from. */
typedef struct plait_aero_block {
	int count, capacity;
	int (*triangle)[3];
	float (*weight)[3];
	int *material;
} plait_aero_block;

typedef struct plait_collider {
	int object;
	plait_shape shape;
	plait_transform transform_start, transform_end; /* keyframes at frame start and end */
	plait_rigid rigid_start, rigid_end;             /* interpolated, current substep */
	/* Deforming mesh colliders (NULL for every other): vertex positions in shape space at the
	 * frame's start and end; the mesh shape follows them substep by substep. */
	vec3 *mesh_start, *mesh_end;
	float thickness, friction, stickiness, bounce;
	bool collide;
	/* A mesh or box collider's vertices as pinned particles [first, first + count) (count 0 for
	 * the other shapes), with a surface of its triangles: in mesh contacts cloth meets the
	 * collider's corners and edges as well as its faces, and an edge or corner sharper than the
	 * cloth's triangles cannot pass between their vertices. They follow the collider substep by
	 * substep (plait_colliders_begin_substep). */
	int first, count;
	/* A closed mesh collider's clearances (NULL for every other, or when out of memory): per
	 * particle, a point in shape space and how far outside the collider it is (its signed
	 * distance there; -INFINITY: unknown), and the collider's drift when it was measured. The
	 * drift (shape space units) sums the longest vertex move of every substep so far (0 for a
	 * rigid mesh, which stands still in its space): every point of the surface keeps within the
	 * drift since of where it was. That distance then changes by no more than the distance moved
	 * plus the drift since, so a particle whose path keeps within clearance - radius - drift
	 * since of that point cannot touch the collider and is passed over (contact.c). */
	vec3 *clear_at;
	float *clearance;
	double *clear_drift;
	int clear_capacity;
	double drift;
} plait_collider;

/* A cloth's surface as other objects' vertices see it: its triangles (object-local indices)
 * with a hierarchy whose boxes are refitted to the particles' swept positions. */
typedef struct plait_surface {
	int object;
	int material;
	int first; /* first particle of the cloth */
	struct plait_mesh_shape *shape;
} plait_surface;

/* A curve as other objects see it in collisions: the chain of segments from particle first to
 * first + count - 1. */
typedef struct plait_chain {
	int object;
	int material;
	int first, count;
} plait_chain;

typedef struct plait_particle_contact {
	int i, j;
	vec3 normal;          /* from i to j */
	float approach_speed; /* relative normal velocity before the substep (negative: closing) */
	float bounce;
} plait_particle_contact;

/* Built-in constraint kinds; their names are what plait explain prints. */
typedef enum plait_kind {
	PLAIT_KIND_STRETCH = 0,
	PLAIT_KIND_SHEAR,
	PLAIT_KIND_BEND,
	PLAIT_KIND_TETHER,
	PLAIT_KIND_COLLISION,
	PLAIT_KIND_CONTACT, /* a contact pass: the last collision iteration's contacts again (contact.h) */
	PLAIT_KIND_COUNT
} plait_kind;

typedef struct plait_settings {
	float fps, time_scale, space_scale;
	int substeps, max_collision_iterations;
	int contact_pass_interval; /* stretch iterations per collision iteration or contact pass; 0: none */
	vec3 gravity;              /* scene units / s^2 */
	float air_density;
	vec3 wind_velocity; /* scene units / s */
	float wind_noise;
	uint32_t seed;
	bool cloth_contacts;
	bool untangle; /* search for crossings to undo (mesh_contact_untangle.c) */
} plait_settings;

typedef struct plait_sim {
	plait_allocator allocator;
	plait_settings settings;
	plait_particles particles;
	int material_count, material_capacity;
	plait_material *materials;
	/* Whether every material of free particles (all but colliders' and destroyed objects') has
	 * the same damp_factor this frame, and that factor: the particle passes then need not read
	 * each particle's material. */
	bool damp_shared;
	float shared_damp_factor;
	plait_distance_block stretch, shear;
	plait_distance_block bend_distance; /* bend as distances across vertices (PLAIT_BEND_DISTANCE) */
	plait_bend_block bend;
	plait_rod_bend_block rod_bend;
	plait_tether_block tether;
	plait_aero_block aero;
	int collider_count, collider_capacity;
	plait_collider *colliders;
	int surface_count, surface_capacity;
	plait_surface *surfaces;
	int chain_count, chain_capacity;
	plait_chain *chains;
	void *mesh_contacts;      /* plait_mesh_contacts, owned by mesh_contact.c */
	bool mesh_contacts_dirty; /* objects came or went: rebuild the collision elements */
	bool mesh_contacts_active;
	bool mesh_contacts_dirty_objects; /* the particle -> collision object map needs a refresh */

	/* Importance per kind, and whether it has work; the schedule is rebuilt when they change. */
	int kind_importance[PLAIT_KIND_COUNT];
	bool kind_active[PLAIT_KIND_COUNT];
	int schedule_kinds[PLAIT_KIND_COUNT]; /* schedule kind index -> plait_kind */
	plait_schedule schedule;
	bool schedule_dirty;
	bool colouring_dirty; /* constraints were added or removed since they were last coloured */
	/* Fold a substep's closing tethers and collisions into its last particle pass when they
	 * allow it (solver.c, fold_closing_passes); always on but for tests comparing the two. */
	bool fold_closing_passes;
	long long folded_substeps; /* substeps that ran folded, since the sim was made (for tests) */
	/* Run a folded close on the points as columns when it can (solver.c, "Columns"); always on
	 * but for tests comparing the two. */
	bool close_on_columns;
	long long closed_on_columns; /* substeps whose close ran on columns (for tests) */
	/* Run a frame as one wave down the regions when it allows it (solver.c, "Waves"); always on
	 * but for tests and benchmarks comparing the two. */
	bool wave_frames;
	/* The distance blocks' boundaries are banded alike: no particle is held by constraints of two
	 * cuts, in one block or across them (set when the blocks are coloured; wave.h). */
	bool bands_agree;
	long long waved_frames; /* frames that ran as a wave, since the sim was made (for tests) */
	/* With several workers, the wave in pieces (wave.h): planned once for a frame's shape; NULL
	 * with one worker or without banded blocks. */
	struct plait_wave_plan *wave_plan;
	long long pieced_frames; /* frames that ran as a wave on several threads (for tests) */

	/* Scratch of the particle-pair stage (spatial hash and contacts). */
	bool particle_pairs_active;
	int pair_contact_count, pair_contact_capacity;
	plait_particle_contact *pair_contacts;
	void *hash;                    /* plait_particle_hash, owned by contact.c */
	int *pair_list;                /* particles taking part in particle-pair collisions */
	vec3 *pair_lower, *pair_upper; /* their swept, thickened boxes */
	int pair_list_capacity;

	/* Contact passes (contact.h): whether the schedule has any, and the particles that touched
	 * something at the last collision iteration, which they go over again. */
	bool contact_passes;
	int *contact_particles;
	int contact_particle_count, contact_particle_capacity;

	/* How the hot loops run: the kernel of the chosen instruction set and the workers. */
	plait_simd simd;
	void (*distance_kernel)(struct plait_distance_block *block, plait_point *points, int begin, int end,
	                        float inverse_h_squared);
	void (*bend_kernel)(struct plait_bend_block *block, plait_point *points, int begin, int end,
	                    float inverse_h_squared);
	plait_parallel parallel;
	/* The points as columns while the distance blocks are projected, when the blocks' segments
	 * hold 8 constraints or more on average (solver.c, "Columns"): x, y, z and w arrays of columns_capacity
	 * floats each, one allocation. in_columns: they hold the current points and the point array is stale. */
	float *column_x, *column_y, *column_z, *column_w;
	int columns_capacity;
	plait_column_ops column_ops; /* of the chosen instruction set */
	bool use_columns, in_columns;

	float largest_radius; /* of any particle, scene units; measured at the start of each step */

	int frame;
	double time;        /* seconds simulated */
	float substep_time; /* h, seconds */
	int substep;        /* current substep in the frame */
	/* Per-frame counters. */
	int contacts;
	int constraint_solves;
	int ccd_hits;
	int failsafe;
	int tangles; /* edge-triangle crossings found at substeps' starts (mesh_contact_untangle.c) */
	double collision_seconds;
} plait_sim;

#endif
