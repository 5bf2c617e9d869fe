// A memo that many threads read and fill at once: keys to values that never change once
// stored. Shards, each an open-addressing table behind its own mutex: a lookup is one or two
// cache lines. (TBB's concurrent_unordered_map walks a linked list per lookup and allocates a
// node per entry: its lookups showed up as a large share of stage 4's profile.)
#pragma once
#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <mutex>
#include <vector>

namespace vdbwrap {

template <typename Key, typename Value, typename Hash>
class ConcurrentMemo {
 public:
  using key_type = Key;
  using mapped_type = Value;

  // The value stored for key, if any.
  bool find(const Key& key, Value& value) const {
    const size_t h = Hash{}(key);
    const Shard& shard = shards_[shard_of(h)];
    std::lock_guard<std::mutex> lock(shard.mutex);
    const Slot* slot = shard.lookup(key, h);
    if (!slot || !slot->used) return false;
    value = slot->value;
    return true;
  }
  // Stores value for key unless the key has one already (the first one stays).
  void insert(const Key& key, const Value& value) {
    const size_t h = Hash{}(key);
    Shard& shard = shards_[shard_of(h)];
    std::lock_guard<std::mutex> lock(shard.mutex);
    if (2 * (shard.count + 1) > shard.slots.size()) shard.grow();
    Slot* slot = const_cast<Slot*>(shard.lookup(key, h));
    if (slot->used) return;
    *slot = {key, value, true};
    ++shard.count;
  }
  size_t size() const {
    size_t n = 0;
    for (const Shard& s : shards_) {
      std::lock_guard<std::mutex> lock(s.mutex);
      n += s.count;
    }
    return n;
  }

 private:
  static constexpr size_t kShards = 256;
  // The shard from the hash's top bits, the slot from its low bits: independent choices.
  static size_t shard_of(size_t h) { return (h >> (8 * sizeof(size_t) - 8)) & (kShards - 1); }
  struct Slot {
    Key key;
    Value value;
    bool used;
  };
  struct alignas(64) Shard {
    mutable std::mutex mutex;
    std::vector<Slot> slots;  // a power of two, at most half full
    size_t count = 0;
    // The slot holding key, or the free slot where it would go (null while there are none).
    const Slot* lookup(const Key& key, size_t h) const {
      if (slots.empty()) return nullptr;
      const size_t mask = slots.size() - 1;
      for (size_t i = h & mask;; i = (i + 1) & mask)
        if (!slots[i].used || slots[i].key == key) return &slots[i];
    }
    void grow() {
      std::vector<Slot> old(std::max<size_t>(64, 2 * slots.size()));
      for (Slot& s : old) s.used = false;
      old.swap(slots);
      for (const Slot& s : old)
        if (s.used) *const_cast<Slot*>(lookup(s.key, Hash{}(s.key))) = s;
    }
  };
  std::array<Shard, kShards> shards_;
};

}  // namespace vdbwrap
