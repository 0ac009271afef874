// SPDX-License-Identifier: Apache-2.0
#include "ido/geometry/triangle_mesh.h"
