#include "json_write.h"

void plait_json_put_string(FILE *f, const char *text)
{
	fputc('"', f);
	for (const char *c = text; *c != '\0'; ++c) {
		unsigned char byte = (unsigned char)*c;
		if (*c == '"' || *c == '\\')
			fprintf(f, "\\%c", *c);
		else if (byte < 0x20)
			fprintf(f, "\\u%04x", (unsigned)byte);
		else
			fputc(*c, f);
	}
	fputc('"', f);
}
