// Private to the library and its tests: how simplify() schedules its collapses, so that the tests
// can hold the region-parallel fast path against slow, obvious schedules (tests/unit/vectorize/
// simplify_test.cpp).
#pragma once

#include <cstdint>

#include "subvec/vectorize/simplify.h"

namespace subvec::detail {

enum class SimplifySchedule : uint8_t {
  kRegionsThenGlobal,  // simplify(): 2 x 2 regions with frozen seams in parallel, then one global pass
  kGlobal,             // one global pass from the start, on one queue
  kRegionsOnly,        // the region phase alone: the mesh it leaves, not simplified further
  kRegionsSerial,      // the region phase as one global pass: one queue over every region on one
                       // thread, seams frozen, each region stopping at its own count
};

// simplify() with a given schedule. The region phase runs when the mesh has more than 16 times
// the target's vertices; otherwise every schedule is one global pass (kRegionsOnly and
// kRegionsSerial then leave the mesh as it is).
SimplifyStats simplify_scheduled(ControlMesh& mesh, int width, int height, const SimplifyOptions& options,
                                 SimplifySchedule schedule);

}  // namespace subvec::detail
