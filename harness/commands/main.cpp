#include "harness/commands/cli.hpp"

int main(int argc, char** argv) { return dsb::harness_main(argc, argv); }
