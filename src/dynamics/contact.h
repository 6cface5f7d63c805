/* The collision kind (paper §7): run as the last kind of every substep by the scheduler, with
 * as many iterations as max_collision_iterations asks (never fewer than the substeps).
 *
 * Each iteration tests, for every colliding particle, the motion from its position at the start
 * of the substep to its current iterate (the space-time path) against every collider moving
 * from its start-of-substep to its end-of-substep transform, and against nearby particles of
 * other objects (and of the same particle object when it self-collides). A hit projects the
 * current position back to the contact surface (inverse-mass weighted between particles),
 * applies Coulomb friction to the tangential displacement of the substep, and records the
 * contact; after the substep's velocity update, restitution (bounce) and stickiness act on the
 * recorded contacts. Friction, stickiness and bounce of a contact are the averages of the two
 * surfaces; friction is clipped at 1 (seed 000 §5.5). */
#ifndef PLAIT_DYNAMICS_CONTACT_H
#define PLAIT_DYNAMICS_CONTACT_H

#include "dynamics/sim.h"

/* Friction of a contact: the average of the two surfaces', clipped at 1 (seed 000 §5.5). */
float plait_combined_friction(float a, float b);

/* Interpolates the collider transforms for the substep [t0, t1] (fractions of the frame). */
void plait_colliders_begin_substep(plait_sim *sim, float t0, float t1);
/* Forgets every clearance of a closed mesh collider (sim.h): after its mesh went back in time. */
void plait_collider_forget_clearances(plait_collider *c);

/* Decides which particles pair up in the substep and clears its pair contacts. (Each
 * particle's contact flags are cleared as the substep begins: solver.c.) */
bool plait_contacts_begin_substep(plait_sim *sim);

/* One collision iteration. */
void plait_collide(plait_sim *sim);

/* A contact pass (the schedule's "contact" events, between collision iterations): the particles
 * that touched a collider at the collision iterations before it go through the collider pass
 * again, and the listed mesh contact pairs that pushed at the last iteration are projected
 * again (plait_mesh_contacts_project_again); nothing new is looked for. Stretch iterations pull
 * a cloth resting on something back into it between collision iterations, and at three substeps
 * and the default resistances that left cloth over a table's rim 2.7 times its length; contact
 * passes hold it out at a small part of a collision iteration's cost. Deterministic, as the
 * iterations are: the same particles and pairs in the same order. */
void plait_collide_again(plait_sim *sim);

/* A pass of particles against one collider in a substep: the collider's bounds over it. */
typedef struct plait_collider_job {
	plait_sim *sim;
	const plait_collider *c;
	bool bounded;
	vec3 world_lower, world_upper; /* box of the collider over the substep, grown */
	vec3 ball_centre;              /* a ball holding the collider over the substep, grown */
	float ball_radius;
	bool still;         /* the same placement at both ends of the substep: surface velocity zero */
	bool identity;      /* still, and shape space is world space: no transforms at all */
	const int *indices; /* the particles to test, or NULL for all */
	/* With indices, from plait_collide_listed_with_colliders: per particle, >= 0 for those in
	 * indices; and where to add the others that triangle pushes move (indices, its count). */
	int *listed;
	int *grown_indices, *grown_count;
	_Atomic int contacts;
	/* Friction also where a particle pushed earlier in the substep rests on the collider without
	 * pressing in (contact.c, rub_resting): a collision iteration's first pass over the colliders
	 * only, so that the pass back over them (an elbow's crease) and the failsafe move particles
	 * with pushes alone. */
	bool rests;
	/* A contact pass's (plait_collide_again): particles pushed out, no friction, no triangle
	 * pushes. */
	bool again;
} plait_collider_job;

#define PLAIT_PASS_COLLIDERS 8

/* A collision iteration a range of particles at a time, for the frame loop to fold into a pass
 * over particles (solver.c): when the iteration is colliders only, each particle on its own
 * (no particle pairs or mesh contacts, no cloth triangles pushed out of round colliders, no
 * collider with vertices of its own, at most PLAIT_PASS_COLLIDERS colliders), every particle
 * meets the colliders in plait_collide's order, with plait_collide's results. */
typedef struct plait_collider_pass {
	int count, reverse_count;
	plait_collider_job jobs[PLAIT_PASS_COLLIDERS];
	plait_collider_job reverse[PLAIT_PASS_COLLIDERS];
} plait_collider_pass;

/* False when the iteration cannot go particle by particle (then plait_collide). */
bool plait_collider_pass_begin(plait_sim *sim, plait_collider_pass *pass);
void plait_collider_pass_range(plait_collider_pass *pass, int begin, int end);
/* Whether the pass can run on the points as columns (every collider bounded, over all
 * particles), and the pass so (solver.c, "Columns"), to the same bits; only where the column
 * kernels run (AVX-512). The point array is scratch there: written for the particles that may
 * reach a collider (and the last few of each 256), stale for the others. */
bool plait_collider_pass_on_columns(const plait_collider_pass *pass);
void plait_collider_pass_range_on_columns(plait_collider_pass *pass, const plait_columns *columns, int begin,
                                          int end);
/* Adds the pass's contacts to the frame's. */
void plait_collider_pass_end(plait_sim *sim, plait_collider_pass *pass);

/* The collider part of an iteration for the particles indices[0, *count) only (after the
 * failsafe moved them); listed[i] >= 0 exactly for those. A cloth triangle dipping into a round
 * collider is pushed out whole: each particle it moves that was not listed is added (listed[i]
 * = i, appended to indices, *count grows), so that the caller knows every particle it moved
 * (the failsafe sweeps again around them; indices needs room for every particle). */
int plait_collide_listed_with_colliders(plait_sim *sim, int *indices, int *count, int *listed);

/* Restitution on the particle-pair contacts of the substep (after v = (x - x_prev) / h), then
 * bounce and stickiness on the mesh contacts (plait_mesh_contacts_restitute). */
void plait_contacts_end_substep(plait_sim *sim);

/* Below this approach speed (scene units / s) a contact rests rather than bounces. */
float plait_resting_speed(const plait_sim *sim);

/* Restitution and stickiness of particle i's collider contact in the substep (it has
 * PLAIT_PARTICLE_CONTACT): its velocity v after the substep, from v_before, the velocity it
 * had before the constraints. */
vec3 plait_respond_to_collider_contact(const plait_particles *p, int i, vec3 v_before, vec3 v,
                                       float resting_speed);

/* Vertices deeper than a tolerance inside any collider, at the current positions. */
int plait_count_penetrations(const plait_sim *sim);

void plait_contacts_destroy(plait_sim *sim);

#endif
