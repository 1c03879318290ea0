#pragma once
// Counts heap allocations: a test binary that links counting_allocator.cc has global operator
// new replaced by one that counts while asked to (one binary per such test: the replacement is
// process-wide).

namespace hpa::test_support {

/// Heap allocations (every form of operator new) made by f().
template <typename F>
long CountAllocations(const F& f);

/// Starts counting from zero.
void StartCountingAllocations();
/// Stops counting and returns the allocations since StartCountingAllocations().
long StopCountingAllocations();

template <typename F>
long CountAllocations(const F& f) {
  StartCountingAllocations();
  f();
  return StopCountingAllocations();
}

}  // namespace hpa::test_support
