// Software prefetch for loops over a sparse or shuffled subset of a model's arrays (the near
// contact pairs, the opened interfaces of the gas in cracks): there each element of each
// array is a cache line of its own, and the loop waits on memory unless it asks for the lines
// a few elements ahead. A prefetch changes no result.
#pragma once
#include <cstddef>

namespace cdem {

// How far ahead the loops ask for their elements' lines (where a loop must first read an index to
// find the data, the index twice as far ahead, so that it is in cache by then). On the late SPEC
// 5.3 state, 16 and 32 were no faster than 8 within the machine's noise.
constexpr std::ptrdiff_t kPrefetchAhead = 8;

// Element i of every array given (for reading).
template <class... T>
inline void prefetch_at(std::size_t i, const T*... a) {
  (__builtin_prefetch(a + i), ...);
}
// Element i of every array given, about to be written.
template <class... T>
inline void prefetch_for_write_at(std::size_t i, T*... a) {
  (__builtin_prefetch(a + i, 1), ...);
}
// Every cache line of one object (a block's face planes: 4 lines).
template <class T>
inline void prefetch_object(const T& x) {
  const char* c = reinterpret_cast<const char*>(&x);
  for (std::size_t off = 0; off < sizeof(T); off += 64) __builtin_prefetch(c + off);
}

}  // namespace cdem
