/* The scene `plait run` simulates when given none: a cloth falling onto a sphere. */
#ifndef PLAIT_DEMO_SCENE_H
#define PLAIT_DEMO_SCENE_H

/* JSON text of the demo; scenes/cloth_on_sphere.json holds the same scene. */
const char *plait_demo_scene_json(void);

#endif
