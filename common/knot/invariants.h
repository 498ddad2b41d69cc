#pragma once
// Knot invariants of a planar diagram, computed exactly: the Alexander polynomial, the
// determinant and signature (Goeritz matrix, Gordon-Litherland) and the Jones polynomial
// (Kauffman bracket state sum). Conventions in common/knot/README.md.

#include <cstdint>

#include "common/knot/diagram.h"
#include "common/knot/laurent_polynomial.h"

namespace microdex::knot {

// Alexander polynomial from the Fox-calculus matrix of the Wirtinger presentation (one row
// per crossing: 1 - t, t, -1 on the over-arc, incoming and outgoing under-arc of a positive
// crossing; t - 1, 1, -t for a negative one), one row and column deleted. The
// determinant is found exactly: evaluated modulo the prime 2^61 - 1 at n points and
// interpolated (coefficients of magnitude below 2^60). Normalised symmetric with a positive
// leading coefficient. Empty coefficients if the result is not a valid Alexander polynomial
// (not symmetric or |Delta(1)| != 1), which only an overflow could cause.
LaurentPolynomial AlexanderPolynomial(const PlanarDiagram& pd);

struct GoeritzResult {
  int signature = 0;
  std::int64_t determinant = 0;  // |det G|, equal to |Delta(-1)|
};
// Signature by Gordon-Litherland: sign(G) - mu, where G is the Goeritz matrix of the
// unshaded faces and mu the correction over the crossings of type II. `shade_color` picks
// which of the two checkerboard colourings is shaded (the result must not depend on it).
GoeritzResult GoeritzSignature(const PlanarDiagram& pd, int shade_color = 0);

// Jones polynomial V(t) from the Kauffman bracket: V = (-A^3)^-w <D> at A = t^(-1/4).
// Exponential in the crossing count (2^n states): call for small diagrams only.
LaurentPolynomial JonesPolynomial(const PlanarDiagram& pd);

}  // namespace microdex::knot
