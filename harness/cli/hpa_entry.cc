// The `hpa` binary: the command line of hpa/scenarios/cli.h.

#include "hpa/scenarios/cli.h"

int main(int argc, char** argv) { return hpa::HpaMain(argc, argv); }
