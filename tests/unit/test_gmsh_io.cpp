#include <gtest/gtest.h>
#include "cdem/mesh/gmsh_io.hpp"
TEST(GmshIo, Placeholder) {}
