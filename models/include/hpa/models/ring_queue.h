#pragma once
// A queue of values appended at the back, dropped from the front and read by index (a filter's
// history of past states, a sensor's messages in flight). Its storage is reused in a ring and only
// grows (doubling) when more entries are kept at once than ever before, so a loop in steady state
// allocates nothing.

#include <cstddef>
#include <iterator>
#include <utility>
#include <vector>

namespace hpa {

/// A double-ended queue of T in a ring of reused slots (push at the back, pop at the front).
template <typename T>
class RingQueue {
 public:
  /// A random-access iterator over the entries, oldest first (std::upper_bound searches them).
  class const_iterator {
   public:
    using iterator_category = std::random_access_iterator_tag;
    using value_type = T;
    using difference_type = std::ptrdiff_t;
    using pointer = const T*;
    using reference = const T&;

    /// A singular iterator; the `index`-th entry of `ring` from the oldest.
    const_iterator() = default;
    const_iterator(const RingQueue* ring, size_t index) : ring_(ring), index_(index) {}
    // the random-access iterator's operators, on the index
    reference operator*() const { return (*ring_)[index_]; }
    pointer operator->() const { return &(*ring_)[index_]; }
    reference operator[](difference_type n) const { return (*ring_)[index_ + n]; }
    const_iterator& operator++() { return ++index_, *this; }
    const_iterator& operator--() { return --index_, *this; }
    const_iterator operator++(int) { return const_iterator(ring_, index_++); }
    const_iterator operator--(int) { return const_iterator(ring_, index_--); }
    const_iterator& operator+=(difference_type n) { return index_ += n, *this; }
    const_iterator& operator-=(difference_type n) { return index_ -= n, *this; }
    const_iterator operator+(difference_type n) const { return const_iterator(ring_, index_ + n); }
    const_iterator operator-(difference_type n) const { return const_iterator(ring_, index_ - n); }
    difference_type operator-(const const_iterator& o) const {
      return static_cast<difference_type>(index_) - static_cast<difference_type>(o.index_);
    }
    bool operator==(const const_iterator& o) const { return index_ == o.index_; }
    bool operator!=(const const_iterator& o) const { return index_ != o.index_; }
    bool operator<(const const_iterator& o) const { return index_ < o.index_; }
    bool operator>(const const_iterator& o) const { return index_ > o.index_; }
    bool operator<=(const const_iterator& o) const { return index_ <= o.index_; }
    bool operator>=(const const_iterator& o) const { return index_ >= o.index_; }

   private:
    const RingQueue* ring_ = nullptr;
    size_t index_ = 0;  // entries from the oldest
  };

  /// Entries kept; whether there are none.
  size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  /// The i-th entry from the oldest (i < size()).
  T& operator[](size_t i) { return slots_[(head_ + i) & mask_]; }
  const T& operator[](size_t i) const { return slots_[(head_ + i) & mask_]; }
  /// The oldest and the newest entry (not empty()).
  T& front() { return (*this)[0]; }
  const T& front() const { return (*this)[0]; }
  T& back() { return (*this)[size_ - 1]; }
  const T& back() const { return (*this)[size_ - 1]; }
  /// The oldest entry and one past the newest.
  const_iterator begin() const { return const_iterator(this, 0); }
  const_iterator end() const { return const_iterator(this, size_); }

  /// Appends `value` as the newest entry (the ring doubles when full).
  void push_back(T value) {
    if (size_ == slots_.size()) Grow();
    slots_[(head_ + size_) & mask_] = std::move(value);
    ++size_;
  }
  /// Drops the oldest entry; its slot keeps the value until reused (move it out first to free
  /// what it holds).
  void pop_front() {
    head_ = (head_ + 1) & mask_;
    --size_;
  }
  /// Drops every entry (the slots are kept, as pop_front keeps them).
  void clear() { head_ = size_ = 0; }

 private:
  // Twice the slots (at least 16), the entries moved to the start in order.
  void Grow() {
    std::vector<T> grown(slots_.empty() ? 16 : 2 * slots_.size());
    for (size_t i = 0; i < size_; ++i) grown[i] = std::move((*this)[i]);
    slots_ = std::move(grown);
    mask_ = slots_.size() - 1;
    head_ = 0;
  }

  std::vector<T> slots_;  // a power of two of them, or none yet
  size_t mask_ = 0;       // slots_.size() - 1
  size_t head_ = 0;       // slot of the oldest entry
  size_t size_ = 0;       // entries kept
};

}  // namespace hpa
