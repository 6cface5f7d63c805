#include "edit_distance.h"

#include <ctype.h>
#include <string.h>

#define PLAIT_EDIT_MAX 64

static int plait_min3(int a, int b, int c)
{
	int m = a < b ? a : b;
	return m < c ? m : c;
}

int plait_edit_distance(const char *a, const char *b)
{
	int n = (int)strlen(a), m = (int)strlen(b);
	if (n > PLAIT_EDIT_MAX || m > PLAIT_EDIT_MAX)
		return PLAIT_EDIT_MAX * 2;
	// Full table (65x65 ints on the stack): the swap rule needs row i-2.
	int d[PLAIT_EDIT_MAX + 1][PLAIT_EDIT_MAX + 1];
	for (int i = 0; i <= n; ++i)
		d[i][0] = i;
	for (int j = 0; j <= m; ++j)
		d[0][j] = j;
	for (int i = 1; i <= n; ++i) {
		for (int j = 1; j <= m; ++j) {
			int ca = tolower((unsigned char)a[i - 1]), cb = tolower((unsigned char)b[j - 1]);
			int cost = ca == cb ? 0 : 1;
			d[i][j] = plait_min3(d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost);
			if (i > 1 && j > 1 && ca == tolower((unsigned char)b[j - 2]) &&
			    tolower((unsigned char)a[i - 2]) == cb && d[i - 2][j - 2] + 1 < d[i][j])
				d[i][j] = d[i - 2][j - 2] + 1;
		}
	}
	return d[n][m];
}

const char *plait_closest_name(const char *word, const char *const *candidates, int count)
{
	const char *best = NULL;
	int best_distance = PLAIT_EDIT_MAX * 2;
	for (int i = 0; i < count; ++i) {
		int distance = plait_edit_distance(word, candidates[i]);
		if (distance < best_distance) {
			best_distance = distance;
			best = candidates[i];
		}
	}
	// Allow about one edit per three letters (at least 2) so "stiffness" does not suggest "seed".
	int length = (int)strlen(word);
	int limit = length / 3 > 2 ? length / 3 : 2;
	if (best != NULL && best_distance <= limit && best_distance < length)
		return best;
	return NULL;
}
