// NodeCache, see node_cache.h (El-Sana & Chiang 2000: buffer management with a free list whose
// entries can be reclaimed without I/O until their memory is reused).
#include "node_cache.h"

#include <cassert>

namespace octolod::runtime {

std::uint64_t mesh_bytes(const NodeMesh& mesh) {
  return (std::uint64_t{mesh.vertices.size()} + std::uint64_t{mesh.indices.size()}) * 4u;
}

NodeCache::NodeCache(const TreeLayout& tree, std::uint64_t budget_bytes)
    : tree_(tree), budget_(budget_bytes), slots_(tree.slot_error.size()),
      subtree_resident_(tree.nodes.size(), 0) {}

void NodeCache::request(std::uint32_t slot) {
  Slot& s = slots_[slot];
  assert(s.state == SlotState::absent && "request() of a slot that is not absent");
  s.state = SlotState::requested;
  reserved_bytes_ += tree_.slot_bytes[slot];
}

void NodeCache::cancel(std::uint32_t slot) {
  Slot& s = slots_[slot];
  assert(s.state == SlotState::requested && "cancel() of a slot that is not requested");
  s.state = SlotState::absent;
  reserved_bytes_ -= tree_.slot_bytes[slot];
}

void NodeCache::mark_bad(std::uint32_t slot) {
  cancel(slot);
  slots_[slot].state = SlotState::bad;
}

void NodeCache::install(std::uint32_t slot, std::shared_ptr<const NodeMesh> mesh, std::uint32_t frame) {
  cancel(slot);
  const std::uint64_t bytes = mesh_bytes(*mesh);
  assert(bytes <= tree_.slot_bytes[slot] && "install() of a mesh larger than its reservation: check_node_lod it first");
  Slot& s = slots_[slot];
  s.mesh = std::move(mesh);
  s.bytes = bytes;
  s.triangles = static_cast<std::uint32_t>(s.mesh->triangle_count());
  s.state = SlotState::resident;
  s.in_use = false;
  s.released = false;
  s.last_used = frame;
  free_bytes_ += bytes;
  short_from_ = kNoSlot;
  link_tail(slot);
  count_resident(slot, +1);
}

void NodeCache::use(std::uint32_t slot, std::uint32_t frame) {
  Slot& s = slots_[slot];
  assert(s.state == SlotState::resident && "use() of a slot that is not resident");
  s.last_used = frame;
  if (s.in_use) return;
  unlink(slot);
  s.in_use = true;
  free_bytes_ -= s.bytes;
  in_use_bytes_ += s.bytes;
}

void NodeCache::release(std::uint32_t slot) {
  Slot& s = slots_[slot];
  if (!s.in_use || s.pinned) return;
  s.in_use = false;
  s.released = true;
  short_from_ = kNoSlot;
  in_use_bytes_ -= s.bytes;
  free_bytes_ += s.bytes;
  link_tail(slot);
}

void NodeCache::touch(std::uint32_t slot, std::uint32_t frame) {
  Slot& s = slots_[slot];
  if (s.state != SlotState::resident) return;
  s.last_used = frame;
  if (s.in_use) return;
  unlink(slot);
  link_tail(slot);
}

void NodeCache::pin(std::uint32_t slot) {
  use(slot, slots_[slot].last_used);
  slots_[slot].pinned = true;
}

bool NodeCache::make_room(std::uint64_t bytes, std::uint32_t protect_from_frame) {
  const std::uint64_t held = in_use_bytes_ + free_bytes_ + reserved_bytes_;
  if (held + bytes <= budget_) return true;
  // Even reclaiming every free entry would not do: keep them all.
  if (in_use_bytes_ + reserved_bytes_ + bytes > budget_) return false;
  const std::uint64_t needed = held + bytes - budget_;
  // An earlier walk found fewer unprotected bytes at this level or a lower one (fewer free
  // entries below it): do not walk again.
  if (short_from_ != kNoSlot && protect_from_frame <= short_from_ && needed > short_bytes_) return false;
  // Entries are reclaimed only once enough are found: reclaiming them for a request that then
  // fails would empty the second-chance list for nothing. Protected entries sit mostly near the
  // tail (touched ones move there), so the walk rarely passes many before it has found room.
  victims_.clear();
  std::uint64_t found = 0;
  for (std::uint32_t s = head_; s != kNoSlot && found < needed; s = slots_[s].next)
    if (slots_[s].last_used < protect_from_frame) {
      victims_.push_back(s);
      found += slots_[s].bytes;
    }
  if (found < needed) {
    short_from_ = protect_from_frame;
    short_bytes_ = found;
    return false;
  }
  for (const std::uint32_t s : victims_) reclaim(s);
  return true;
}

void NodeCache::reclaim(std::uint32_t slot) {
  Slot& s = slots_[slot];
  unlink(slot);
  free_bytes_ -= s.bytes;
  s.mesh.reset();
  s.bytes = 0;
  s.triangles = 0;
  s.state = SlotState::absent;
  s.released = false;
  count_resident(slot, -1);
}

void NodeCache::link_tail(std::uint32_t slot) {
  Slot& s = slots_[slot];
  s.prev = tail_;
  s.next = kNoSlot;
  if (tail_ != kNoSlot) slots_[tail_].next = slot;
  else head_ = slot;
  tail_ = slot;
}

void NodeCache::unlink(std::uint32_t slot) {
  Slot& s = slots_[slot];
  if (s.prev != kNoSlot) slots_[s.prev].next = s.next;
  else head_ = s.next;
  if (s.next != kNoSlot) slots_[s.next].prev = s.prev;
  else tail_ = s.prev;
  s.prev = s.next = kNoSlot;
}

void NodeCache::count_resident(std::uint32_t slot, int delta) {
  for (auto n = static_cast<std::int32_t>(tree_.slot_node[slot]); n >= 0;
       n = tree_.nodes[static_cast<std::size_t>(n)].parent) {
    auto& c = subtree_resident_[static_cast<std::size_t>(n)];
    c = static_cast<std::uint32_t>(static_cast<std::int64_t>(c) + delta);
  }
}

}  // namespace octolod::runtime
