#pragma once
/// Values keyed by a small non-negative id (agent ids: 0..9999), as std::map would hold them (ascending
/// ids when iterated, pairs of id and value) but in one contiguous array found by one index look-up.
/// Made for what a receiver does with the swarm many thousand times a second (find an agent, update it,
/// walk all of them); inserting an id is linear in the ids above it, which happens once per agent.
/// Inserting or erasing moves the values: references and iterators are good until the next insertion
/// or erasure (std::map's stay good).
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace shapeform::util {

template <class T>
class IdMap {
 public:
  using value_type = std::pair<std::int32_t, T>;
  using iterator = typename std::vector<value_type>::iterator;
  using const_iterator = typename std::vector<value_type>::const_iterator;

  iterator begin() { return items_.begin(); }
  iterator end() { return items_.end(); }
  const_iterator begin() const { return items_.begin(); }
  const_iterator end() const { return items_.end(); }
  std::size_t size() const { return items_.size(); }
  bool empty() const { return items_.empty(); }

  iterator find(std::int32_t id) {
    const int k = slot(id);
    return k < 0 ? items_.end() : items_.begin() + k;
  }
  const_iterator find(std::int32_t id) const {
    const int k = slot(id);
    return k < 0 ? items_.end() : items_.begin() + k;
  }
  bool contains(std::int32_t id) const { return slot(id) >= 0; }

  /// The value of id; throws std::out_of_range when there is none.
  T& at(std::int32_t id) {
    const int k = slot(id);
    if (k < 0) throw std::out_of_range("IdMap::at: no id " + std::to_string(id));
    return items_[static_cast<std::size_t>(k)].second;
  }
  const T& at(std::int32_t id) const { return const_cast<IdMap*>(this)->at(id); }

  /// The value of id, a default-constructed one inserted if there is none. Throws std::out_of_range
  /// for a negative id (no slot to index it by).
  T& operator[](std::int32_t id) {
    if (const int k = slot(id); k >= 0) return items_[static_cast<std::size_t>(k)].second;
    return insert(id, T{});
  }
  /// id's value set to value (inserted if there is none); throws as operator[] does.
  T& insert_or_assign(std::int32_t id, T value) {
    if (const int k = slot(id); k >= 0) return items_[static_cast<std::size_t>(k)].second = std::move(value);
    return insert(id, std::move(value));
  }

  /// Removes id (if there); returns how many were removed (0 or 1).
  std::size_t erase(std::int32_t id) {
    const int k = slot(id);
    if (k < 0) return 0;
    items_.erase(items_.begin() + k);
    pos_[static_cast<std::size_t>(id)] = -1;
    reindex(static_cast<std::size_t>(k));
    return 1;
  }
  /// Removes every pair for which pred(pair) is true, in one pass; returns how many.
  template <class Pred>
  std::size_t erase_if(Pred pred) {
    const std::size_t before = items_.size();
    std::size_t kept = 0;
    for (std::size_t k = 0; k < items_.size(); ++k) {
      if (pred(const_cast<const value_type&>(items_[k]))) {
        pos_[static_cast<std::size_t>(items_[k].first)] = -1;
      } else {
        if (kept != k) items_[kept] = std::move(items_[k]);
        pos_[static_cast<std::size_t>(items_[kept].first)] = static_cast<int>(kept);
        ++kept;
      }
    }
    items_.resize(kept);
    return before - kept;
  }
  void clear() {
    items_.clear();
    pos_.clear();
  }

 private:
  std::vector<value_type> items_;  ///< ascending ids
  std::vector<int> pos_;           ///< pos_[id]: the index of id in items_, -1 if absent

  /// Inserts id (absent) with value, in order.
  T& insert(std::int32_t id, T value) {
    if (id < 0) throw std::out_of_range("IdMap: negative id " + std::to_string(id));
    // Appending is the common case (ids heard in ascending order); else the first id above goes up one.
    std::size_t k = items_.size();
    while (k > 0 && items_[k - 1].first > id) --k;
    items_.insert(items_.begin() + static_cast<std::ptrdiff_t>(k), value_type(id, std::move(value)));
    if (static_cast<std::size_t>(id) >= pos_.size()) pos_.resize(static_cast<std::size_t>(id) + 1, -1);
    reindex(k);
    return items_[k].second;
  }
  int slot(std::int32_t id) const {
    const auto k = static_cast<std::size_t>(id);
    return id < 0 || k >= pos_.size() ? -1 : pos_[k];
  }
  void reindex(std::size_t from) {
    for (std::size_t k = from; k < items_.size(); ++k) pos_[static_cast<std::size_t>(items_[k].first)] = static_cast<int>(k);
  }
};

}  // namespace shapeform::util
