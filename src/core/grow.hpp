// Capacity with headroom for arrays that are resized at every neighbor build to about the
// same length (list entries, history records, cells). std::vector reallocates to exactly the
// new length whenever it grows by even one element, and a fresh block of megabytes is then
// faulted in page by page (a chute's 2.7 MB of history records took 1 ms a build, more than
// carrying the history over). Growing by an eighth more than asked makes that rare.
#pragma once
#include <cstddef>

namespace cohdem {

/// Ensures v can hold n elements without reallocating, growing to n + n/8 when it cannot.
template <class V>
void reserve_headroom(V& v, size_t n) {
  if (v.capacity() < n) v.reserve(n + n / 8 + 64);
}

/// Grows v to at least n elements (never shrinks it), with headroom as above.
template <class V>
void grow_to(V& v, size_t n) {
  if (v.size() < n) {
    reserve_headroom(v, n);
    v.resize(n);
  }
}

}  // namespace cohdem
