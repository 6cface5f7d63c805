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

#define COLLIDE_SCENE_MAX_CLOTHS 4

typedef struct collide_scene {
	collide_scene_kind kind;
	plait_self_collision_flag self_flag; /* of every self-colliding cloth */
	float thickness_per_edge;            /* hang-self: the cloth's thickness over its edge (0: 4 mm) */
	plait_world_id world;
	plait_object_id cloths[COLLIDE_SCENE_MAX_CLOTHS]; /* lowest first where they are stacked */
	int cloth_count;
	plait_object_id animated; /* the spinning sphere or the forearm */
	int frames;               /* the scene's natural length */
	int frame;                /* frames stepped so far */
	float fps;
} collide_scene;

/* Builds a scene with n x n vertices per sheet (0: the scene's full size). The world def may
 * be NULL (defaults of the scene) or carries thread hooks and the like. */
bool collide_scene_create(collide_scene *scene, collide_scene_kind kind, int n, const plait_world_def *base,
                          plait_error *error);
/* As collide_scene_create, with the self-colliding cloths' self-collision flag, and for
 * hang-self a thickness in proportion to the cloth's edge (thickness_per_edge > 0; 0: 4 mm at
 * any resolution). */
bool collide_scene_create_flagged(collide_scene *scene, collide_scene_kind kind, int n,
                                  const plait_world_def *base, plait_self_collision_flag self_flag,
                                  float thickness_per_edge, plait_error *error);
/* Moves the animated collider to its place at the end of the next frame, then steps. */
plait_result collide_scene_step(collide_scene *scene, plait_error *error);
void collide_scene_destroy(collide_scene *scene);

/* Vertices of upper cloths found beneath a lower one: along vertical lines for the pile, along
 * lines from the sphere's centre (over its upper cap) for the drape. 0 means the order holds. */
int collide_scene_order_violations(const collide_scene *scene);

#endif
