/* The plait command-line tool; everything but main() lives in plait_toollib. */
#include "cli.h"

#include <stdio.h>

int main(int argc, char **argv)
{
	return plait_cli_main(argc, argv, stdout, stderr);
}
