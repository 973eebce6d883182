// Node order: the same general model with its nodes renumbered, the experiment axis of
// mesh runs (how a pipeline's memory access depends on where neighbours lie in memory).
// A reordered model remembers each node's index in the file (Model::file_node), so that
// results can be reported in the file's order whatever the internal one.
#pragma once
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "model.hpp"

namespace deformlab {

enum class NodeOrder : std::uint8_t {
  file,      // as loaded
  shuffled,  // a seeded random permutation: neighbours anywhere (the worst case)
  rcm,       // reverse Cuthill-McKee: small bandwidth
  morton,    // Z-order of the rest positions: neighbours in space close in memory
};
const char* to_string(NodeOrder o);
std::optional<NodeOrder> parse_node_order(const std::string& s);
inline constexpr const char* kNodeOrderNames = "file, shuffled, rcm, morton";

// The permutation: order[k] is the node that becomes node k.
std::vector<std::int32_t> node_order(const Model& m, NodeOrder o, std::uint64_t seed);

// Renumbers a general model (node order[k] becomes node k): positions, masses, springs (then
// sorted by their new end nodes), triangles and file_node follow; the adjacency is rebuilt.
void reorder(Model& m, const std::vector<std::int32_t>& order);

// Bandwidth: the largest |i - j| over the springs (what node order changes).
std::int64_t bandwidth(const Model& m);

}  // namespace deformlab
