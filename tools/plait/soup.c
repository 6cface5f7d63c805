#include "soup.h"

#include <stdlib.h>

void plait_soup_free(plait_soup *soup)
{
	free(soup->positions);
	free(soup->face_sizes);
	free(soup->face_indices);
	*soup = (plait_soup){0};
}
