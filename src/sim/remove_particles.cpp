// System::remove_particles: deleting particles renumbers the survivors, so the pair and wall
// lists are compacted to the new numbering first (their contact history rides along; the
// survivors keep their order, so every pair stays in the row of its lower index); the next
// neighbor build then carries the history over by id as usual.
#include <cstring>
#include <stdexcept>

#include "sim/system.hpp"

namespace cohdem {

namespace {

/// History of the list entries `kept` (old entry indices, in their new order).
void compact_history(const HistoryArray& old, HistoryArray& nu, const std::vector<uint32_t>& kept) {
  nu.stride = old.stride;
  nu.flip = old.flip;
  nu.resize(kept.size());
  for (size_t q = 0; q < kept.size(); ++q) {
    std::memcpy(nu.at(q), old.data.data() + size_t(kept[q]) * old.stride, old.stride);
    nu.live[q] = old.live[kept[q]];
  }
}

}  // namespace

void System::remove_particles(const std::vector<uint8_t>& remove) {
  const size_t n = particles.size();
  if (opened_) throw std::logic_error("remove_particles in the middle of a step (step_once(true))");
  if (remove.size() != n) throw std::invalid_argument("remove_particles: one flag per particle expected");
  std::vector<int64_t> nu(n, -1);
  int64_t m = 0;
  for (size_t i = 0; i < n; ++i)
    if (!remove[i]) nu[i] = m++;
  if (m == int64_t(n)) return;
  if (nl.start.size() == n + 1) {
    // Pair rows.
    std::vector<uint32_t> start(size_t(m) + 1, 0), jdx, kept;
    std::vector<uint8_t> image;
    for (size_t i = 0; i < n; ++i) {
      if (nu[i] < 0) continue;
      for (uint32_t k = nl.start[i]; k < nl.start[i + 1]; ++k) {
        if (nu[nl.jdx[k]] < 0) continue;
        jdx.push_back(uint32_t(nu[nl.jdx[k]]));
        image.push_back(nl.image[k]);
        kept.push_back(k);
      }
      start[nu[i] + 1] = uint32_t(jdx.size());
    }
    HistoryArray hist;
    compact_history(nl.hist, hist, kept);
    // Wall rows.
    std::vector<uint32_t> wstart(size_t(m) + 1, 0), wkept;
    std::vector<uint16_t> wall;
    for (size_t i = 0; i < n; ++i) {
      if (nu[i] < 0) continue;
      for (uint32_t e = nl.wstart[i]; e < nl.wstart[i + 1]; ++e) { wall.push_back(nl.wall[e]); wkept.push_back(e); }
      wstart[nu[i] + 1] = uint32_t(wall.size());
    }
    HistoryArray whist;
    compact_history(nl.whist, whist, wkept);
    nl.start = std::move(start);
    nl.jdx = std::move(jdx);
    nl.image = std::move(image);
    nl.hist = std::move(hist);
    nl.wstart = std::move(wstart);
    nl.wall = std::move(wall);
    nl.whist = std::move(whist);
    nl.rstart.clear();
    nl.rpair.clear();
  }
  particles.erase_if_flagged(remove);
  dirty_ = true;
}

}  // namespace cohdem
