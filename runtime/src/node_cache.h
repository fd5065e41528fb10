// The byte-budgeted node LOD cache with second chance (El-Sana & Chiang 2000, buffer management;
// seed 000: freed entries stay findable until reused).
//
// A resident slot is either in use (drawn by the current frame, or pinned) or on the free list.
// Entries the frame stops drawing are released to the tail of the free list but keep their data:
// wanting them again costs no I/O (a second-chance hit). Memory is reclaimed from the head of the
// free list (least recently used) only when a new load needs room. In-use entries are never
// reclaimed, so nothing the current frame draws is evicted.
//
// Render thread only.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "octolod/formats/node_file.h"
#include "tree_layout.h"

namespace octolod::runtime {

enum class SlotState : std::uint8_t {
  absent,     // not in memory, not requested
  requested,  // queued or being loaded; its expected size is reserved
  resident,   // in memory: in use or on the free list
  bad,        // failed to load; never requested again
};

class NodeCache {
 public:
  NodeCache(const TreeLayout& tree, std::uint64_t budget_bytes);

  SlotState state(std::uint32_t slot) const { return slots_[slot].state; }
  bool resident(std::uint32_t slot) const { return slots_[slot].state == SlotState::resident; }
  // Resident, on the free list, and drawn before: wanting it now is a second-chance hit.
  bool second_chance(std::uint32_t slot) const {
    const Slot& s = slots_[slot];
    return s.state == SlotState::resident && !s.in_use && s.released;
  }
  const std::shared_ptr<const NodeMesh>& mesh(std::uint32_t slot) const { return slots_[slot].mesh; }
  // The resident mesh's triangle count, without touching the mesh's own memory.
  std::uint32_t triangles(std::uint32_t slot) const { return slots_[slot].triangles; }
  // Resident slots in the subtree of `node` (internal index), the node itself included.
  std::uint32_t subtree_resident(std::uint32_t node) const { return subtree_resident_[node]; }

  // requested <-> absent, keeping the reservation of the expected size.
  void request(std::uint32_t slot);
  void cancel(std::uint32_t slot);
  void mark_bad(std::uint32_t slot);  // from requested
  // requested -> resident (on the free list, most recent). The mesh takes over the request's
  // reservation, which it must fit (mesh_bytes at most the slot's expected bytes: a loaded mesh
  // has the manifest's counts, check_node_lod), so installing never needs room or evicts.
  void install(std::uint32_t slot, std::shared_ptr<const NodeMesh> mesh, std::uint32_t frame);

  // Frame bookkeeping: use() takes a resident slot off the free list (drawn in `frame`);
  // release() puts an in-use slot at the free list's tail, keeping the frame it was last used in;
  // touch() marks a resident slot wanted in `frame` and moves a free one to the tail.
  void use(std::uint32_t slot, std::uint32_t frame);
  void release(std::uint32_t slot);
  void touch(std::uint32_t slot, std::uint32_t frame);
  void pin(std::uint32_t slot);  // in use forever
  bool in_use(std::uint32_t slot) const { return slots_[slot].in_use; }
  bool pinned(std::uint32_t slot) const { return slots_[slot].pinned; }
  std::uint32_t last_used(std::uint32_t slot) const { return slots_[slot].last_used; }

  // Reclaims free entries, least recently used first, until `bytes` more fit in the budget next
  // to everything resident and reserved. Entries used or touched at or after `protect_from_frame`
  // are kept. False when it cannot make room; then nothing is reclaimed.
  bool make_room(std::uint64_t bytes, std::uint32_t protect_from_frame);

  std::uint64_t resident_bytes() const { return in_use_bytes_ + free_bytes_; }
  std::uint64_t reserved_bytes() const { return reserved_bytes_; }
  std::uint64_t budget() const { return budget_; }

 private:
  struct Slot {
    std::shared_ptr<const NodeMesh> mesh;
    std::uint64_t bytes = 0;  // real size while resident
    std::uint32_t triangles = 0;  // of the mesh while resident
    std::uint32_t prev = kNoSlot, next = kNoSlot;  // free list links
    std::uint32_t last_used = 0;
    SlotState state = SlotState::absent;
    bool in_use = false;
    bool released = false;
    bool pinned = false;
  };

  void link_tail(std::uint32_t slot);
  void unlink(std::uint32_t slot);
  void reclaim(std::uint32_t slot);
  void count_resident(std::uint32_t slot, int delta);

  const TreeLayout& tree_;
  std::uint64_t budget_;
  std::vector<Slot> slots_;
  std::vector<std::uint32_t> subtree_resident_;
  std::uint32_t head_ = kNoSlot, tail_ = kNoSlot;
  // When not kNoSlot: a make_room walk found only short_bytes_ in free entries used before this
  // frame. Cleared when an entry joins the free list (leaving it only lowers what a walk finds).
  std::uint32_t short_from_ = kNoSlot;
  std::uint64_t short_bytes_ = 0;
  std::vector<std::uint32_t> victims_;  // make_room's scratch: the entries it will reclaim
  std::uint64_t in_use_bytes_ = 0, free_bytes_ = 0, reserved_bytes_ = 0;
};

// Bytes a NodeMesh holds in the cache: its vertex floats and 32-bit indices.
std::uint64_t mesh_bytes(const NodeMesh& mesh);

}  // namespace octolod::runtime
