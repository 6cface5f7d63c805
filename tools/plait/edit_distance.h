/* Closest-name suggestions for typos ("did you mean ...?"). */
#ifndef PLAIT_EDIT_DISTANCE_H
#define PLAIT_EDIT_DISTANCE_H

/* Optimal string alignment distance, case-insensitive: insertions, deletions, substitutions and
 * swaps of two neighbours each cost 1. Strings longer than 64 bytes compare as far apart. */
int plait_edit_distance(const char *a, const char *b);

/* The candidate closest to word if it is close enough to be a plausible typo, else NULL. */
const char *plait_closest_name(const char *word, const char *const *candidates, int count);

#endif
