// The CDEM topology builder (SPEC 1): split every mesh vertex into one node per block, find
// every face (3D) or edge (2D) shared by two blocks and make it an interface with one spring
// point per coincident node pair, assign block and interface materials by region.
#pragma once
#include <array>
#include <cstdint>
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

// Every face (3D) or edge (2D) of every element, its vertex ids sorted (key, -1 padded), the list
// sorted by key: equal neighbours are one face shared by their blocks (an interface), a key met
// once a boundary face. Block b is element order[b] (build_model's block order; the identity for
// a graph of the mesh's elements).
struct FaceRec {
  std::array<std::int32_t, 3> key;
  std::int32_t block;
  std::int8_t local;  // the face's index in the element (local_faces)
  bool operator<(const FaceRec& o) const {
    return key != o.key ? key < o.key : (block != o.block ? block < o.block : local < o.local);
  }
};
std::vector<FaceRec> sorted_faces(const Mesh& mesh, const std::vector<std::int32_t>& order);

}  // namespace cdem
