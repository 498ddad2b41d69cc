#include "common/geometry/arc_torus.h"
