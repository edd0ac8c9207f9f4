// The CDEM topology builder (SPEC 1): split every mesh vertex into one node per block, find
// every face (3D) or edge (2D) shared by two blocks and make it an interface with one spring
// point per coincident node pair, assign block and interface materials by region.
#pragma once
#include <string>
#include <vector>

#include "cdem/mesh/mesh.hpp"
#include "cdem/model/model.hpp"

namespace cdem {

// `where` prefixes error messages (the case file name). Throws InputError when a region has no
// material, a material names a region the mesh lacks, a region pair has no interface material,
// or the mesh is non-manifold (a face shared by more than two elements).
Model build_model(const Mesh& mesh, const std::vector<BlockMaterial>& block_materials,
                  const std::vector<InterfaceMaterial>& iface_materials, const std::string& where);

}  // namespace cdem
