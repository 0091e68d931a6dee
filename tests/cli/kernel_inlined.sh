#!/usr/bin/env bash
# The force loops keep their contact law inline (docs/performance-history.md, eighth round): GCC's
# inliner gives up inside the kernels' large OpenMP functions, and a restructured loop once
# left ContactLaw::evaluate, then every sub-model, as calls (3-10 % of a chute's speed, and
# nothing else showed it). This lists the calls in each `compute(...) [clone ._omp_fn.N]`
# of the optimized binary (and in the region function each of them runs, compute's
# `region`) and fails on any call into cohdem's own code other than the wall
# geometry (rare entries), the wall contacts of a particle (ContactModelImpl::wall_contacts,
# kept out of line on purpose: only particles with wall entries call it), the thread
# split's set-up (PairSlots, once per list build), the AVX2 screening of a batch
# (screen_avx2 or screen_avx512: compiled for AVX2 or AVX-512 alone, so they cannot be inlined into the portable kernel),
# the finish of free particles four at a time (finish_free_avx2: one call per run of them,
# AVX2 alone for the same reason), the region function from its parallel region and a vector's destructor (once a call each),
# the contacts of the laws with lanes (linear_, hertz_, mepa_lanes_avx2 and _avx512 and their
# _epsd_ forms, and hertz_sds_: one call per 16 contacts, AVX2 or AVX-512 alone for the same reason), the highest partner of a
# batch in the two-step sweep (max_index_avx2: one call per batch, AVX2 alone), the prefetch of
# a sparse batch's rows (prefetch_rows: one call per batch with few contacts, kept out of line
# so that the dense batches' code is as before) and the cold exception paths. Libraries (libm's pow, cbrt, cos;
# libgomp; operator new/delete) are allowed. Skipped, saying so, for a build that is not
# optimized (Debug), where nothing is inlined.
set -u
bin=$1
cache="$(dirname "$bin")/CMakeCache.txt"
type=$(sed -n 's/^CMAKE_BUILD_TYPE:STRING=//p' "$cache" 2>/dev/null)
case "$type" in
  Release|RelWithDebInfo|MinSizeRel) ;;
  *) echo "SKIP: build type '$type' is not optimized; the inlining check needs Release"; exit 0 ;;
esac
command -v objdump > /dev/null || { echo "FAIL objdump not found (package binutils, scripts/install-deps.sh)"; exit 1; }
objdump -d --no-show-raw-insn -C "$bin" | awk '
  /^[0-9a-f]+ <.*>:$/ {
    fn = $0
    # the region run by every thread (or called directly on one thread: compute(...)::
    # {lambda(...)#1}, the first lambda defined in compute whose parameters start with the
    # contact history), and the parallel region that calls it
    k = index(fn, "::compute(cohdem::ForceContext&) const [clone ._omp_fn.") > 0 || \
        (index(fn, "::compute(cohdem::ForceContext&) const::{lambda(") > 0 && index(fn, "State*") > 0 && index(fn, "operator()") > 0)
    if (k) kernels++
    next
  }
  k && /\tcall/ {
    t = $0; sub(/.*call +[0-9a-f]* */, "", t)
    if (t ~ /@plt>/ || t ~ /operator (new|delete)/ || t ~ /std::__throw/ || t ~ /\[clone \.cold\]/ || t ~ /cohdem::Wall::/ || t ~ /cohdem::PairSlots::/ || t ~ />::wall_contacts\(/ || t ~ /cohdem::screen_avx2\(/ || t ~ /cohdem::screen_avx512\(/ || t ~ /cohdem::finish_free_avx2\(/ || t ~ /cohdem::max_index_avx2\(/ || t ~ /cohdem::prefetch_rows\(/ || t ~ /cohdem::(linear|hertz|mepa)(_epsd|_sds)?_lanes_avx(2|512)\(/ || (t ~ /::compute\(cohdem::ForceContext&\) const::\{lambda\(/ && t ~ /State\*/) || t ~ /std::vector<.*>::~vector\(\)/) next
    bad[t]++
  }
  END {
    n = 0
    for (t in bad) { print "FAIL call in a force loop: " t; n++ }
    if (kernels < 10) { print "FAIL found only " kernels " force-loop functions to check"; n++ }
    if (n == 0) print "ok   " kernels " force-loop functions, no call into cohdem code but wall geometry, wall contacts and set-up"
    exit n > 0
  }'
