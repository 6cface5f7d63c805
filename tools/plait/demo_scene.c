#include "demo_scene.h"

// A 1.6 m square of 40x40 quads dropped from 1.2 m onto a 0.5 m sphere resting on the ground;
// it folds onto itself as it drapes, so it collides with itself (without, its folds crossed each
// other in 110 of the 120 frames).
static const char plait_demo_json[] =
    "{\n"
    "  \"world\": {\"fps\": 24, \"substeps\": 3, \"gravity\": [0, -9.81, 0]},\n"
    "  \"frames\": 120,\n"
    "  \"objects\": [\n"
    "    {\"name\": \"cloth\", \"type\": \"cloth\",\n"
    "     \"grid\": {\"size\": [1.6, 1.6], \"resolution\": [40, 40], \"center\": [0, 1.2, 0]},\n"
    "     \"thickness\": 0.01, \"friction\": 0.3, \"self_collide\": true},\n"
    "    {\"name\": \"sphere\", \"type\": \"collider\", \"shape\": \"sphere\",\n"
    "     \"center\": [0, 0.5, 0], \"radius\": 0.5, \"friction\": 0.3},\n"
    "    {\"name\": \"ground\", \"type\": \"collider\", \"shape\": \"plane\",\n"
    "     \"point\": [0, 0, 0], \"normal\": [0, 1, 0], \"friction\": 0.5}\n"
    "  ]\n"
    "}\n";

const char *plait_demo_scene_json(void)
{
	return plait_demo_json;
}
