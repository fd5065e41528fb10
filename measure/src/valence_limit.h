// A decimater module for the reference (reference.cpp): vetoes a half-edge collapse that would
// leave its kept vertex with more neighbours than a limit and than either end has now.
//
// OpenMesh's DecimaterT re-ranks every neighbour of a collapsed vertex by trying each of that
// neighbour's outgoing half-edges, and each try walks the one-rings of the edge's ends: a vertex
// of valence V costs about V² per re-ranking, and it is re-ranked at every collapse beside it.
// Where greedy quadric collapses gather a hub (an open tube's quads collapse along its length
// into its end rings, whose vertices then fan out along the tube), V grows with the mesh and the
// decimation turns cubic: a 32-sided open tube of 32,000 triangles took 81 s to reach 1%, one of
// 64,000 more than 15 minutes (docs/benchmarks.md).
#pragma once

#include <algorithm>

#include <OpenMesh/Tools/Decimater/ModBaseT.hh>

namespace octolod::measure {

template <class MeshT>
class ModValenceLimitT : public OpenMesh::Decimater::ModBaseT<MeshT> {
 public:
  DECIMATING_MODULE(ModValenceLimitT, MeshT, ValenceLimit);

  // Binary: it allows or forbids collapses; the quadric module ranks them. No limit until set.
  explicit ModValenceLimitT(MeshT& mesh) : Base(mesh, true) {}

  void set_max_valence(unsigned max_valence) { max_valence_ = max_valence; }

  float collapse_priority(const CollapseInfo& ci) override {
    const unsigned from = Base::mesh().valence(ci.v0), to = Base::mesh().valence(ci.v1);
    // v1 keeps the neighbours of both ends but not the ends themselves, and the far corners of
    // the triangles beside the edge (vl, vr), neighbours of both, once
    const unsigned shared = (ci.vl.is_valid() ? 1u : 0u) + (ci.vr.is_valid() ? 1u : 0u);
    const unsigned after = from + to - 2u - shared;
    // a vertex already above the limit (an input's pole) may still lose neighbours
    const bool grows = after > max_valence_ && after > std::max(from, to);
    return static_cast<float>(grows ? Base::ILLEGAL_COLLAPSE : Base::LEGAL_COLLAPSE);
  }

 private:
  unsigned max_valence_ = ~0u;
};

}  // namespace octolod::measure
