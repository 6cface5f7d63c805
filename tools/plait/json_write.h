/* Small pieces of JSON written by hand, where a line at a time is all there is to write. */
#ifndef PLAIT_JSON_WRITE_H
#define PLAIT_JSON_WRITE_H

#include <stdio.h>

/* text as a JSON string, quotes included. */
void plait_json_put_string(FILE *f, const char *text);

#endif
