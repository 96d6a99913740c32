// How the CLI uses memory (docs/vectorize.md, "Speed"). A vectorization allocates a few hundred
// MB in large, short-lived arrays, stage after stage. By default glibc gives every freed block
// over 128 KB back to the kernel, so each stage faults its fresh pages in again, 4 KB at a time;
// on virtual machines, where a page fault is dear, that was a third of a run.
//
// tune_memory() keeps freed memory in the process for reuse (the peak resident size is what it
// was; it is just not given back before exit), puts every thread on one heap, and grows that
// heap once by a large reserve that asks the kernel for 2 MB pages (transparent huge pages,
// honoured where they are set to "madvise" or "always"). The reserve is address space only: pages
// become resident when first written. Without glibc it does nothing.
//
// Tried and dropped: mapping the reserve ahead on a helper thread (MADV_POPULATE_WRITE) while the
// serial stages run. It slowed the stages' own page faults more than it saved.
#pragma once

#include <cstddef>
#include <cstdint>

namespace subvec_cli {

void tune_memory();

// After tune_memory(): grows the reserve to `bytes` when it is smaller, so that a job expected to
// need more than the first reserve (vectorizing a large photograph: its estimate) gets huge
// pages too. Address space only, as the first reserve; it fails quietly.
void reserve_memory(int64_t bytes);

// The process's peak resident size so far (getrusage), in bytes; 0 where it cannot tell.
int64_t peak_resident_bytes();

}  // namespace subvec_cli
