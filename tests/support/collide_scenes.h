/* The collision scenes of issue #3, built through the public API, for the tests (at sizes that
 * fit a test run) and bench/bench_collide.c (at full size). Each is a world plus what animates
 * its colliders from frame to frame, and the measures the tests check: crossing triangles per
 * frame, and whether cloths that started one above another are still in that order. */
#ifndef PLAIT_COLLIDE_SCENES_H
#define PLAIT_COLLIDE_SCENES_H

#include <plait/plait.h>

typedef enum collide_scene_kind {
	SCENE_DRAPE,     /* two sheets falling onto a sphere and the ground, one over the other */
	SCENE_THIN_BOX,  /* a sheet thrown at 20 m/s onto a box 1 mm thick */
	SCENE_PILE,      /* four sheets falling into a pile on the ground, self-collision on */
	SCENE_TWIST,     /* a sheet on a sphere that spins about its vertical axis (twisting test) */
	SCENE_ARM,       /* a tube of cloth over a capsule arm that bends at the elbow */
	SCENE_HANG_SELF, /* hang-N over a sphere given as a mesh of ~5000 triangles, self-collision on */
	SCENE_COUNT
} collide_scene_kind;

extern const char *const collide_scene_names[SCENE_COUNT];

#define COLLIDE_SCENE_MAX_CLOTHS 5

/* Variations of the scenes for benchmarks and tests. */
typedef struct collide_scene_options {
	plait_self_collision_flag self_flag; /* of every self-colliding cloth */
	/* hang-self: the thickness a share of the cloth's edge (> 0), not 4 mm at any resolution */
	float thickness_per_edge;
	/* hang-self: the constraints of issue 4's comparison (structural, shear and skip-one edges,
	 * all rigid, 6 substeps of one sweep each, Euclidean tethers), not the default resistances,
	 * under which 1 kg a vertex stretches the edges at the pins a thousandfold */
	bool stiff;
	/* hang-self: the sphere mesh's slices and stacks (0: 50, about 4,900 triangles) */
	int sphere_slices;
	/* hang-self: the sphere's radius, m (0: 0.5); its top stays 25 cm under the cloth */
	float sphere_radius;
	/* hang-self with stiff: substeps a frame, one sweep of each constraint kind in each (0: 6).
	 * A finer cloth needs more to hold together as well as a coarser one (bench_hang). */
	int stiff_substeps;
	/* 0: the scene as defined. k > 0: every cloth starts shifted by k times (0.7, 0, 0.3) mm in
	 * scene units, one of a family of nearby starts: a chaotic scene (folds, a pile) takes each
	 * its own way, so a change to the solver can be judged over several outcomes, not one. */
	int variant;
	/* The world's contact_pass_interval (plait_world_def); -1: the def's as given */
	int contact_pass_interval;
	/* arm: the upper arm and forearm as closed triangle meshes of their capsules (912 triangles
	 * each); drape and twist: the sphere as a closed mesh of 40 slices and stacks (3,120
	 * triangles); not analytic shapes */
	bool mesh_colliders;
	/* twist: the sphere mesh (mesh_colliders) turned by moving its vertices frame by frame, a
	 * deforming mesh collider, not by its transform; arm: one closed mesh of the whole arm whose
	 * vertices bend at the elbow frame by frame (a skinned arm: the axis bends along an arc 20 cm
	 * long), not two rigid capsules */
	bool deforming_colliders;
	/* arm: the upper arm and forearm as square box bars 10 cm across, not capsules (their
	 * vertices, edges and faces meet the sleeve in the mesh contacts) */
	bool box_colliders;
	/* pile: the four sheets fall onto a coarse sheet lying on the ground (3 x 3 vertices, 1.2 m
	 * across, its corners pinned), whose long edges and large triangles make contact pairs
	 * that reach across the slabs a long list is planned in (mesh_contact_plan.c) */
	bool coarse_floor;
} collide_scene_options;

typedef struct collide_scene {
	collide_scene_kind kind;
	collide_scene_options options;
	plait_world_id world;
	plait_object_id cloths[COLLIDE_SCENE_MAX_CLOTHS]; /* lowest first where they are stacked */
	int cloth_count;
	plait_object_id animated; /* the spinning sphere or the forearm (or the deforming arm) */
	/* A deforming collider's vertices at rest and as posed for the next frame (NULL when none) */
	plait_vec3 *rest, *posed;
	int rest_count;
	int frames; /* the scene's natural length */
	int frame;  /* frames stepped so far */
	float fps;
} collide_scene;

/* Builds a scene with n x n vertices per sheet (0: the scene's full size). The world def may
 * be NULL (defaults of the scene) or carries thread hooks and the like. */
bool collide_scene_create(collide_scene *scene, collide_scene_kind kind, int n, const plait_world_def *base,
                          plait_error *error);

/* The default options: every scene as collide_scene_create makes it. */
collide_scene_options collide_scene_default_options(void);

/* As collide_scene_create, with options. */
bool collide_scene_create_with(collide_scene *scene, collide_scene_kind kind, int n,
                               const plait_world_def *base, const collide_scene_options *options,
                               plait_error *error);
/* Moves the animated collider to its place at the end of the next frame, then steps. */
plait_result collide_scene_step(collide_scene *scene, plait_error *error);
void collide_scene_destroy(collide_scene *scene);

/* Vertices of upper cloths found beneath a lower one: along vertical lines for the pile, along
 * lines from the sphere's centre (over its upper cap) for the drape. 0 means the order holds. */
int collide_scene_order_violations(const collide_scene *scene);

#endif
