/* plait: a unified dynamics solver for cloth, curves and particles.
 *
 * Public API, in the style of Box2D v3: definition structs filled by plait_default_*_def(),
 * opaque ids passed by value, plait_noun_verb names, no global state. Every function that can
 * fail takes an optional plait_error* (may be NULL) and says why in plain words.
 *
 * Units: metres, seconds, kilograms, degrees for user-facing rotations. With space_scale s, one
 * scene unit is s metres: positions stay in scene units, gravity and wind are converted.
 */
#ifndef PLAIT_PLAIT_H
#define PLAIT_PLAIT_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define PLAIT_VERSION_MAJOR 0
#define PLAIT_VERSION_MINOR 1
#define PLAIT_VERSION_PATCH 0

/* ---- Basic types ---------------------------------------------------------------------------- */

typedef struct plait_vec3 {
	float x, y, z;
} plait_vec3;

typedef enum plait_result {
	PLAIT_OK = 0,
	PLAIT_ERROR_INVALID_ARGUMENT, /* a value out of its documented range, a NULL pointer, ... */
	PLAIT_ERROR_INVALID_ID,       /* a world or object id that is stale or was never valid */
	PLAIT_ERROR_INVALID_MESH,     /* bad index, non-finite coordinate, degenerate topology */
	PLAIT_ERROR_OUT_OF_MEMORY,
	PLAIT_ERROR_NONFINITE, /* the simulation produced NaN or infinity */
} plait_result;

#define PLAIT_ERROR_MESSAGE_SIZE 256

/* Filled by any failing call that was given one. message is a readable sentence. */
typedef struct plait_error {
	plait_result code;
	char message[PLAIT_ERROR_MESSAGE_SIZE];
} plait_error;

const char *plait_result_name(plait_result result);

/* Ids are opaque handles passed by value; zero-initialised ids are null. There is no global
 * registry (no global state): an id carries its world, so ids of a destroyed world must not be
 * used again. Object ids carry a generation, so a destroyed object's id is detected as stale. */
struct plait_world;
typedef struct plait_world_id {
	struct plait_world *world;
} plait_world_id;

typedef struct plait_object_id {
	struct plait_world *world;
	int32_t index1; /* 1-based object slot, 0 = null */
	uint16_t generation;
} plait_object_id;

static inline bool plait_world_id_is_null(plait_world_id id)
{
	return id.world == NULL;
}
static inline bool plait_object_id_is_null(plait_object_id id)
{
	return id.index1 == 0;
}

/* ---- Hooks ---------------------------------------------------------------------------------- */

/* Allocator hooks; all NULL means malloc/free. alignment is a power of two <= 64. */
typedef void *plait_alloc_fn(size_t size, size_t alignment, void *user_context);
typedef void plait_free_fn(void *memory, void *user_context);

/* Task system hooks (Box2D shape). The world splits work into item ranges and calls
 * enqueue_task; the user runs task(start, end, worker_index, task_context) on any thread for
 * each range (or all at once) and finish_task waits for it. With worker_count > 1, each task
 * must start on a thread of its own without waiting for finish_task: the world keeps
 * worker_count - 1 tasks running for a frame, which take their work as it comes (a task not
 * started, or a NULL handle, only costs speed). Results never depend on how the work is
 * scheduled. If enqueue_task is NULL everything runs on the calling thread. A task uses up to
 * about 32 KB of its thread's stack. */
typedef void plait_task_fn(int start_index, int end_index, int worker_index, void *task_context);
typedef void *plait_enqueue_task_fn(plait_task_fn *task, int item_count, int min_range, void *task_context,
                                    void *user_context);
typedef void plait_finish_task_fn(void *user_task, void *user_context);

/* ---- World ---------------------------------------------------------------------------------- */

typedef struct plait_wind_def {
	float speed;          /* m/s (converted by space_scale), >= 0 */
	plait_vec3 direction; /* normalised internally; zero vector = no wind */
	float noise;          /* 0..1 (up to 10): random turbulence as a fraction of speed */
} plait_wind_def;

/* Instruction set of the solver's hot kernels. Every level gives bit-identical results; AUTO
 * picks the widest this processor runs. Asking for a level the processor lacks is an error. */
typedef enum plait_simd {
	PLAIT_SIMD_AUTO = 0,
	PLAIT_SIMD_SCALAR, /* portable C */
	PLAIT_SIMD_AVX2,   /* x86-64 with AVX2: 8 lanes */
	PLAIT_SIMD_AVX512, /* x86-64 with AVX-512F: 16 lanes */
} plait_simd;

typedef struct plait_world_def {
	float fps;                    /* frames per second, > 0 (24) */
	int substeps;                 /* substeps per frame, 1..1000 (3) */
	int max_collision_iterations; /* collision iterations per frame, 0..1000 (4); never fewer than substeps */
	/* Contact passes (a "contact" in plait explain's schedule) between a substep's collision
	 * iterations, so that stretch iterations do not pull cloth into what it rests on: each
	 * enforces again the contacts the last collision iteration found (vertices on colliders,
	 * cloth pairs that pushed), at a small part of an iteration's cost. A collision iteration or
	 * a contact pass at least once every this many stretch iterations, at most 8 of them a
	 * substep; 0: none, only the collision iterations, as before contact passes existed (1).
	 * Without them cloth resting on a collider at the default substeps ends stretched where it
	 * rests (docs/architecture.md, "Contact passes"). */
	int contact_pass_interval;
	plait_vec3 gravity; /* m/s^2 (0, -9.81, 0); scaled by 1/space_scale */
	float air_density;  /* kg/m^3, >= 0 (1.0) */
	plait_wind_def wind;
	float space_scale; /* metres per scene unit, > 0 (1) */
	float time_scale;  /* simulated seconds per real second of frame time, > 0 (1) */
	uint32_t seed;     /* seed of the wind noise (0) */
	/* Cloths collide with other objects through their triangles: vertex-triangle and edge-edge
	 * contacts with the other cloths, curves and particles, continuous, with a failsafe that
	 * keeps them from passing through each other (true). Self-collision of a cloth is its own
	 * flag, plait_cloth_def.self_collide. */
	bool cloth_contacts;
	/* Crossings between cloths, or within a self-colliding cloth, or of curves through cloth,
	 * that a scene begins with (or that positions set from outside make) are found and undone
	 * over the next frames, counted in plait_frame_stats.tangles (true). False leaves them as
	 * they are, held by the contacts and the failsafe, and skips the search at the first
	 * substep (for scenes built to begin free of crossings). */
	bool untangle;

	plait_alloc_fn *alloc;
	plait_free_fn *free;
	void *allocator_context;

	plait_enqueue_task_fn *enqueue_task;
	plait_finish_task_fn *finish_task;
	void *task_context;
	int worker_count; /* threads the task system offers, >= 1 (1) */
	plait_simd simd;  /* PLAIT_SIMD_AUTO */

	int internal_value; /* set by plait_default_world_def(); checks the def was initialised */
} plait_world_def;

plait_world_def plait_default_world_def(void);

plait_world_id plait_create_world(const plait_world_def *def, plait_error *error);
void plait_destroy_world(plait_world_id world);
bool plait_world_is_valid(plait_world_id world);

/* Advance one frame (1/fps seconds times time_scale). Fails with PLAIT_ERROR_NONFINITE if any
 * particle became non-finite, or PLAIT_ERROR_OUT_OF_MEMORY; the positions and velocities are
 * then left as they were at the start of the frame. */
plait_result plait_world_step(plait_world_id world, plait_error *error);

/* The instruction set the world's kernels run with (never AUTO), and whether a level runs on
 * this processor. */
plait_simd plait_world_get_simd(plait_world_id world);
bool plait_simd_is_supported(plait_simd simd);

/* Current frame number (0 after creation) and simulated time in seconds. */
int plait_world_get_frame(plait_world_id world);
double plait_world_get_time(plait_world_id world);

/* Change settings between frames. The def's hooks (allocator, task system) are ignored: those of
 * the world's creation stay. */
plait_result plait_world_set_def(plait_world_id world, const plait_world_def *def, plait_error *error);
plait_world_def plait_world_get_def(plait_world_id world);

/* ---- The schedule (paper §6): which kinds of constraint run, in which order ---------------- */

#define PLAIT_MAX_KIND_NAME 24

/* Events of one substep, in the order they run: kind names such as "stretch", "bend",
 * "collision". Returns the number of events; writes at most capacity names. */
int plait_world_get_substep_count(plait_world_id world);
int plait_world_get_schedule(plait_world_id world, int substep, const char **names, int capacity);

/* ---- Objects -------------------------------------------------------------------------------- */

typedef enum plait_object_type {
	PLAIT_OBJECT_CLOTH = 0,
	PLAIT_OBJECT_CURVE,
	PLAIT_OBJECT_PARTICLES,
	PLAIT_OBJECT_COLLIDER,
} plait_object_type;

/* Attributes common to every object. Friction, stickiness and bounce of a contact are the
 * average of the two surfaces (friction clipped at 1, seed 000 §5.5). */
typedef struct plait_surface_def {
	float thickness;  /* collision radius around the surface, scene units, >= 0 */
	float friction;   /* Coulomb coefficient, 0..10 (0.1) */
	float stickiness; /* 0..1: share of separating normal velocity removed while touching (0) */
	float bounce;     /* restitution, 0..1 (0) */
	bool collide;     /* takes part in collisions (true) */
	/* 0..1000 (0). Objects on one layer push each other; of two on different layers, the one on
	 * the lower layer pushes the other but is not pushed back, as if it were a collider (an
	 * inner garment under an outer one). */
	int collision_layer;
} plait_surface_def;

/* A mesh as a polygon soup: vertex positions and faces of 3 or 4 (or more) vertices.
 * face_sizes[i] is the vertex count of face i; face_indices lists them back to back.
 * Polygons are fanned from their first vertex; a quad (a,b,c,d) becomes (a,b,c), (a,c,d). */
typedef struct plait_mesh_def {
	const plait_vec3 *positions;
	int vertex_count;
	const int *face_sizes;
	int face_count;
	const int *face_indices;
} plait_mesh_def;

/* Tethers (long-range attachments, seed 004): each free vertex of a cloth is tied to its
 * nearest pinned vertices (up to four) and may never get farther from any of them than its
 * rest distance times tether_scale. They stop a hanging cloth from stretching when iterations
 * are few; tying a vertex to several pins keeps the tethers themselves from pulling apart the
 * cloth where the nearest pin changes. */
typedef enum plait_tether_mode {
	PLAIT_TETHER_NONE = 0,
	PLAIT_TETHER_EUCLIDEAN, /* nearest pins and distances in a straight line in the rest shape */
	PLAIT_TETHER_GEODESIC,  /* nearest pins and distances along the mesh's edges */
} plait_tether_mode;

/* How a cloth resists bending. */
typedef enum plait_bend_model {
	/* The signed angle between the two triangles of each interior edge, against its rest value;
	 * bend_resistance R gives a bending stiffness of R x 1e-4 N m. */
	PLAIT_BEND_DIHEDRAL = 0,
	/* The distance between the two ends of each pair of edges that continue each other (two
	 * edges apart along a line of the mesh): bend_resistance R gives R x 100 N/m, as stretch.
	 * Cheaper, and what mass-spring and NvCloth cloth use; it cannot tell up from down. */
	PLAIT_BEND_DISTANCE,
} plait_bend_model;

/* Which pairs of a self-colliding cloth's own primitives push each other at its self-collision
 * thickness (seed 000 §4.5.1). Whatever the flag, the cloth does not pass through itself: the
 * vertex-triangle and edge-edge pairs it leaves out are swept by the failsafe. */
typedef enum plait_self_collision_flag {
	PLAIT_SELF_COLLIDE_FULL_SURFACE = 0, /* vertex-triangle and edge-edge */
	PLAIT_SELF_COLLIDE_VERTEX_FACE,      /* vertex-triangle only */
	PLAIT_SELF_COLLIDE_VERTEX,           /* vertex-vertex only, spheres of the thickness */
} plait_self_collision_flag;

/* Which of a cloth's primitives meet colliders (seed 000 §4.2: nCloth's collision flag). */
typedef enum plait_collision_flag {
	/* Its vertices against colliders' faces, and its edges and triangles against colliders'
	 * edges, corners and round surfaces: no part of a collider passes between its vertices. */
	PLAIT_COLLIDE_FULL_SURFACE = 0,
	/* Its vertices only (as particle-based cloth solvers do, NvCloth's and Jolt's): cheaper, but
	 * a collider's corner, edge or curved surface can reach between the vertices of triangles
	 * large against it (a sphere of radius R by up to about (longest edge)^2 / 6R). */
	PLAIT_COLLIDE_VERTEX,
} plait_collision_flag;

typedef struct plait_cloth_def {
	const char *name;
	plait_mesh_def mesh;
	const plait_vec3 *velocities; /* optional initial velocities, scene units per second */
	float density;                /* kg/m^2, mass spread by area (0.2) */
	const float *vertex_masses;   /* optional kg per vertex, > 0; replaces density when given */
	/* Resistances: the stiffness of the material and (scaling relation "link", seed 000 §9) the
	 * iterations per frame of that kind. 0 turns the constraint off; the maximum, 10000, makes
	 * it rigid (zero compliance). */
	float stretch_resistance;     /* 0..10000 (20) */
	float compression_resistance; /* 0..10000 (10) */
	float shear_resistance;       /* 0..10000 (10) */
	float bend_resistance;        /* 0..10000 (0.1) */
	plait_bend_model bend_model;  /* (PLAIT_BEND_DIHEDRAL) */
	float rest_length_scale;      /* 0.01..10 (1) */
	float drag;                   /* normal air drag coefficient, >= 0 (0.05) */
	float tangential_drag;        /* >= 0 (0.01) */
	float lift;                   /* >= 0 (0.05) */
	float damp;                   /* velocity damping rate, 1/s, 0..100 (0) */
	int iterations;               /* stretch iterations per frame; 0 = from the stretch and compression
	                               * resistances (0). Lets a stiff material run with few iterations. */
	int shear_iterations;         /* as iterations, for shear (0: from shear_resistance) */
	int bend_iterations;          /* as iterations, for bend (0: from bend_resistance) */
	plait_tether_mode tethers;    /* (PLAIT_TETHER_NONE); built from the pins given here */
	bool self_collide;            /* it collides with itself (false); pairs of its primitives closer than the
	                               * self-collision thickness in the start shape are left to its constraints */
	plait_self_collision_flag self_collision_flag; /* (PLAIT_SELF_COLLIDE_FULL_SURFACE) */
	plait_collision_flag collision_flag;           /* against colliders (PLAIT_COLLIDE_FULL_SURFACE) */
	float self_collide_width_scale;                /* self-collision thickness / thickness, 0.01..100 (1) */
	float tether_scale;                            /* allowed distance / rest distance, 1..10 (1) */
	float tether_stiffness;                        /* share of a tether's excess removed per pass, 0..1 (1) */
	plait_surface_def surface;
	const int *pins; /* vertex indices held at their start position (targets settable later) */
	int pin_count;
} plait_cloth_def;

typedef struct plait_curve_def {
	const char *name;
	const plait_vec3 *positions; /* a chain: vertex i joined to i+1 */
	int vertex_count;
	const plait_vec3 *velocities;
	float mass;                   /* kg per vertex (0.01) */
	float stretch_resistance;     /* 0..10000 (20) */
	float compression_resistance; /* 0..10000 (10) */
	float bend_resistance;        /* 0..10000 (0.1) */
	float rest_length_scale;      /* (1) */
	float drag;                   /* linear air drag per vertex, >= 0 (0) */
	float damp;                   /* 1/s (0) */
	int iterations;               /* as for cloth (0) */
	bool self_collide;            /* its segments collide with each other (false) */
	plait_surface_def surface;
	const int *pins;
	int pin_count;
} plait_curve_def;

typedef struct plait_particles_def {
	const char *name;
	const plait_vec3 *positions;
	int count;
	const plait_vec3 *velocities;
	float mass;                /* kg per particle (1) */
	float radius;              /* scene units, > 0 (0.05) */
	float drag;                /* linear air drag per particle, >= 0 (0) */
	float damp;                /* 1/s (0) */
	plait_surface_def surface; /* thickness adds to radius */
	bool self_collide;         /* particles of this object collide with each other (true) */
} plait_particles_def;

typedef enum plait_shape_type {
	PLAIT_SHAPE_PLANE = 0,
	PLAIT_SHAPE_SPHERE,
	PLAIT_SHAPE_CAPSULE,
	PLAIT_SHAPE_BOX,
	PLAIT_SHAPE_MESH, /* a triangle mesh (polygons are fanned), moved by its transform; rigid
	                   * unless created deforming */
} plait_shape_type;

/* A rigid transform as users write it: translate, then rotation in degrees about x, then y,
 * then z (R = Rz·Ry·Rx), then uniform scale. Applied on top of the shape's own placement. */
typedef struct plait_transform {
	plait_vec3 translate;
	plait_vec3 rotate_deg;
	float scale; /* > 0 (1) */
} plait_transform;

typedef struct plait_collider_def {
	const char *name;
	plait_shape_type shape;
	plait_vec3 point, normal;  /* plane: a point on it and its normal (solid below) */
	plait_vec3 center;         /* sphere, box */
	float radius;              /* sphere, capsule */
	plait_vec3 a, b;           /* capsule segment ends */
	plait_vec3 size;           /* box: full extents */
	plait_vec3 rotation_deg;   /* box: orientation */
	plait_mesh_def mesh;       /* mesh: vertices and faces in the collider's own space */
	bool deforming;            /* mesh: its vertices move too, set frame by frame with
	                            * plait_collider_set_mesh_positions (false); costs more than
	                            * a rigid mesh moved by its transform (docs/scene-format.md) */
	plait_transform transform; /* initial keyframe transform (identity) */
	plait_surface_def surface;
} plait_collider_def;

plait_cloth_def plait_default_cloth_def(void);
plait_curve_def plait_default_curve_def(void);
plait_particles_def plait_default_particles_def(void);
plait_collider_def plait_default_collider_def(void);
plait_transform plait_identity_transform(void);

/* Object creation copies all arrays; the caller keeps ownership of its buffers. */
plait_object_id plait_create_cloth(plait_world_id world, const plait_cloth_def *def, plait_error *error);
plait_object_id plait_create_curve(plait_world_id world, const plait_curve_def *def, plait_error *error);
plait_object_id plait_create_particles(plait_world_id world, const plait_particles_def *def,
                                       plait_error *error);
plait_object_id plait_create_collider(plait_world_id world, const plait_collider_def *def,
                                      plait_error *error);
void plait_destroy_object(plait_object_id object);
bool plait_object_is_valid(plait_object_id object);

plait_object_type plait_object_get_type(plait_object_id object);
const char *plait_object_get_name(plait_object_id object);
int plait_world_get_object_count(plait_world_id world);
plait_object_id plait_world_get_object(plait_world_id world, int index); /* in creation order */

/* Vertices of a cloth, curve or particle object (0 for colliders). */
int plait_object_get_vertex_count(plait_object_id object);
/* Triangles used for collision and drag (quads fanned). Writes 3*capacity ints at most;
 * returns the triangle count. Curves and particles have none. */
int plait_object_get_triangles(plait_object_id object, int *indices, int capacity);
/* Polygon faces as given at creation (for writing meshes). face_sizes/face_indices may be NULL
 * to ask for counts: returns face count; *index_count receives the total index count. */
int plait_object_get_faces(plait_object_id object, int *face_sizes, int *face_indices, int *index_count);

/* Read or write positions (scene units) and velocities (scene units per second) of count
 * vertices starting at first. Writing moves the start state of the next frame; positions set
 * through other cloths (or a self-colliding cloth through itself) are found at the next substep
 * and undone, as a scene that begins tangled is (plait_frame_stats.tangles). */
plait_result plait_object_get_positions(plait_object_id object, int first, int count, plait_vec3 *out,
                                        plait_error *error);
plait_result plait_object_set_positions(plait_object_id object, int first, int count,
                                        const plait_vec3 *positions, plait_error *error);
plait_result plait_object_get_velocities(plait_object_id object, int first, int count, plait_vec3 *out,
                                         plait_error *error);
plait_result plait_object_set_velocities(plait_object_id object, int first, int count,
                                         const plait_vec3 *velocities, plait_error *error);

/* Pins: a pinned vertex follows its target exactly, linearly interpolated over the next frame. */
plait_result plait_object_pin_vertex(plait_object_id object, int vertex, plait_vec3 target,
                                     plait_error *error);
plait_result plait_object_unpin_vertex(plait_object_id object, int vertex, plait_error *error);
plait_result plait_object_set_pin_target(plait_object_id object, int vertex, plait_vec3 target,
                                         plait_error *error);

/* Colliders: the transform reached at the end of the next frame; in between the solver
 * interpolates translate, rotation and scale linearly (seed 000 §2.3). */
plait_result plait_collider_set_transform(plait_object_id collider, plait_transform transform,
                                          plait_error *error);
plait_transform plait_collider_get_transform(plait_object_id collider);
/* Deforming mesh colliders (created with deforming = true): the positions of all count vertices
 * (count must be the mesh's vertex count), in the collider's own space, reached at the end of the
 * next frame. In between each vertex moves on a straight line from where it was at the end of
 * the last frame, and collisions follow the moving triangles (their swept volume in time, seed
 * 000 §2.3); the transform applies on top. Without a new call the mesh keeps its last shape.
 * The faces never change. Fails, changing nothing, for a rigid collider, a wrong count or a
 * non-finite position. */
plait_result plait_collider_set_mesh_positions(plait_object_id collider, const plait_vec3 *positions,
                                               int count, plait_error *error);
/* Signed distance (scene units) from point to the collider's surface, thickness not included; a
 * deforming mesh as it stands at the end of the last frame. */
float plait_collider_signed_distance(plait_object_id collider, plait_vec3 point);

/* ---- Statistics of the last frame ---------------------------------------------------------- */

typedef struct plait_frame_stats {
	int frame;
	double kinetic_energy; /* J, in scene units converted to metres */
	float max_strain;      /* max |length/rest - 1| over stretch edges of all cloths and curves */
	int penetrations;      /* vertices inside a collider (deeper than 1% of their radius) at frame end */
	int nonfinite;         /* non-finite coordinates found at frame end */
	int contacts;          /* contacts resolved in the frame: with colliders, between particles, and
	                        * between the primitives of meshes and curves */
	int ccd_hits;          /* continuous tests that found primitives crossing within a substep */
	int failsafe;          /* last-resort activations: impact zones made rigid, vertices frozen */
	int tangles;           /* triangle edges found crossing other triangles at the substeps' starts
	                        * (a state that began tangled, or positions set through each other),
	                        * summed over the frame; pushed back through until none is left */
	double collision_ms;   /* wall time spent in collisions (detection and response) in the frame */
	int constraint_solves; /* constraint projections performed in the frame */
} plait_frame_stats;

/* Measures of the current state (energy, strain, penetrations, non-finite values: taken when
 * called, so a step costs nothing for them) and the counters of the last frame. */
plait_frame_stats plait_world_get_stats(plait_world_id world);

/* An intersection check of the current state (for tests and users, not used by the solver). */
typedef struct plait_intersection_report {
	int triangle_pairs;         /* pairs of triangles that intersect: between cloths, within one cloth
	                             * for triangles that share no vertex, and between a cloth and a mesh
	                             * or box collider */
	int inside_colliders;       /* vertices inside a collider (below a plane, inside a shape) by more
	                             * than 1e-4 scene units plus 1% of their radius */
	int triangles_in_colliders; /* cloth triangles reaching into a sphere or capsule collider by
	                             * more than that (the other shapes' triangles are in
	                             * triangle_pairs) */
} plait_intersection_report;

plait_result plait_world_check_intersections(plait_world_id world, plait_intersection_report *report,
                                             plait_error *error);

/* Whether two triangles intersect: an edge of one crosses the other, borders included (touching
 * counts); coplanar overlaps are not counted. Orientation signs in double precision: the test
 * plait_world_check_intersections and `plait check` count with. */
bool plait_triangles_intersect(const plait_vec3 a[3], const plait_vec3 b[3]);

/* ---- Collider geometry where the collider is now (for writing it out and checking results) -- */

/* "Now" is the end of the last step (or creation): a transform set for the next frame is not
 * applied yet. Scene units, world space. */
typedef struct plait_collider_shape {
	plait_shape_type type;
	plait_vec3 point, normal; /* plane: a point on it and its unit normal (solid below) */
	plait_vec3 center;        /* sphere, box */
	float radius;             /* sphere, capsule */
	plait_vec3 a, b;          /* capsule segment ends */
	plait_vec3 half_extents;  /* box */
	plait_vec3 axes[3];       /* box: unit directions of its own x, y and z */
} plait_collider_shape;

plait_result plait_collider_get_shape(plait_object_id collider, plait_collider_shape *shape,
                                      plait_error *error);

/* Whether the collider has an inside: spheres, capsules and boxes do, planes do not, and a mesh
 * does when every edge joins exactly two triangles. For a mesh this sorts its edges: ask once. */
bool plait_collider_is_closed(plait_object_id collider);

/* The collider's surface as triangles that never change and vertices that follow it: a mesh's
 * own triangles (polygons fanned); a sphere or capsule tessellated (64 segments around) with
 * every vertex on the surface, so the triangles lie inside the true shape; a box's 12
 * triangles; a plane as a square PLAIT_COLLIDER_PLANE_SIZE across centred on its point.
 * Triangles wind counter-clockwise seen from outside. get_surface_triangles writes 3*capacity
 * ints at most (indices may be NULL) and returns the triangle count; 0 for a non-collider. */
#define PLAIT_COLLIDER_PLANE_SIZE 20.0f
int plait_collider_get_surface_vertex_count(plait_object_id collider);
int plait_collider_get_surface_triangles(plait_object_id collider, int *indices, int capacity);
plait_result plait_collider_get_surface_positions(plait_object_id collider, int first, int count,
                                                  plait_vec3 *out, plait_error *error);

#ifdef __cplusplus
}
#endif

#endif /* PLAIT_PLAIT_H */
