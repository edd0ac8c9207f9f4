// The gas model of a charge's products (a case key: [[hole]] gas), shared by the case and the
// explosive kernels.
#pragma once

namespace cdem {

// The bar's detonation products (docs/theory.md "Bar charges: the gas"): "literal" is SPEC 2 as
// written (each segment's volume V0 (1 + theta_e) from its bound blocks' mean strain, eq. 9);
// "cavity" makes each deck one gas body filling the cavity the rock opens around it (the bound
// blocks' whole volume change), pushing the collar stemming out as a plug and venting through the
// collar; "cracks" adds the opened cracks connected to the charge, which the gas invades and
// pushes apart, and venting where they reach a free surface.
enum class GasModel { Literal, Cavity, Cracks };
inline const char* name_of(GasModel g) {
  return g == GasModel::Literal ? "literal" : (g == GasModel::Cavity ? "cavity" : "cracks");
}

}  // namespace cdem
