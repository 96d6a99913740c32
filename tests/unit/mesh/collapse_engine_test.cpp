// The collapse engine's fast storage (mesh/collapse_engine_p.h, mesh/quadric_p.h) against slow,
// obvious references: the binned lazy queue against sorting every entry, the incidence lists
// against std::vector, the thread-split quadric sums against one serial loop.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <random>
#include <set>
#include <vector>

#include "mesh/collapse_engine_p.h"
#include "mesh/quadric_p.h"

namespace subvec {
namespace {

using detail::CollapseQueue;
using detail::Entry;

// Random entries whose costs span 2^-octaves..2^octaves, 16 bins per octave (and repeat, so that
// ties are broken by the vertices).
std::vector<Entry> random_entries(int n, std::mt19937& rng, double octaves = 20) {
  std::uniform_real_distribution<double> exponent(-octaves, octaves);
  std::uniform_int_distribution<int32_t> vertex(0, 999), repeat(0, 9);
  std::vector<Entry> out;
  for (int i = 0; i < n; ++i) {
    const double cost = repeat(rng) == 0 ? 1.0 : std::exp2(exponent(rng));
    out.push_back(detail::make_entry(cost, vertex(rng), vertex(rng), 0, 0));
  }
  return out;
}

TEST(CollapseQueue, EntriesComeOutInTheOrderOfSortingThemAll) {
  std::mt19937 rng(7);
  const std::vector<Entry> entries = random_entries(20000, rng);
  CollapseQueue queue;
  for (const Entry& e : entries) queue.push(e);
  EXPECT_EQ(queue.size(), entries.size());
  std::vector<Entry> sorted = entries;
  std::sort(sorted.begin(), sorted.end());
  Entry e;
  for (const Entry& want : sorted) {
    ASSERT_TRUE(queue.pop(e, [](const Entry&) { return true; }));
    ASSERT_EQ(e.key, want.key);
    ASSERT_EQ(e.keep, want.keep);
  }
  EXPECT_FALSE(queue.pop(e, [](const Entry&) { return true; }));
  EXPECT_EQ(queue.size(), 0u);
}

TEST(CollapseQueue, InterleavedPushesAndStaleEntriesKeepTheOrderOfOneSortedSet) {
  // Pushes between pops (as collapses re-plan their neighbourhood), some entries stale: the live
  // ones come out exactly as from an ordered set of everything pushed so far, and the queue may
  // drop stale ones unseen but never a live one. Few bins (two octaves), so that many pushes land in
  // the bin at the front.
  std::mt19937 rng(11);
  CollapseQueue queue;
  std::multiset<std::pair<uint64_t, int32_t>> reference;
  const auto live = [](const Entry& e) { return e.keep % 3 != 0; };
  Entry e;
  for (int round = 0; round < 200; ++round) {
    for (const Entry& x : random_entries(100, rng, 1)) {
      queue.push(x);
      if (live(x)) reference.insert({x.key, x.keep});
    }
    for (int i = 0; i < 60; ++i) {
      bool got = false;
      while (queue.pop(e, live)) {
        if (live(e)) {
          got = true;
          break;
        }
      }
      ASSERT_EQ(got, !reference.empty());
      if (!got) break;
      ASSERT_EQ(std::make_pair(e.key, e.keep), *reference.begin());
      reference.erase(reference.begin());
    }
  }
}

TEST(CollapseQueue, EntriesOrderByCostThenRemovedThenKeptVertex) {
  const Entry cheap = detail::make_entry(0.5, 9, 9, 0, 0), dear = detail::make_entry(2.0, 0, 0, 0, 0);
  const Entry a = detail::make_entry(1.0, 3, 8, 0, 0), b = detail::make_entry(1.0, 4, 1, 0, 0),
              c = detail::make_entry(1.0, 4, 2, 0, 0);
  EXPECT_TRUE(cheap < a && a < b && b < c && c < dear);
  EXPECT_EQ(b.remove(), 4);
}

TEST(CollapseQueue, AnEntryIsLiveUntilEitherVertexDiesOrChanges) {
  std::vector<uint8_t> alive{1, 1, 1};
  std::vector<uint32_t> version{0, 5, 70000};
  const Entry e = detail::make_entry(1.0, 1, 2, version[1], version[2]);
  EXPECT_TRUE(detail::entry_live(e, alive, version));
  ++version[2];
  EXPECT_FALSE(detail::entry_live(e, alive, version));
  --version[2];
  alive[1] = 0;
  EXPECT_FALSE(detail::entry_live(e, alive, version));
}

TEST(CollapseQueue, TheGreedyLoopStopsWhenToldAndWhenCancelled) {
  std::mt19937 rng(3);
  CollapseQueue queue;
  for (const Entry& x : random_entries(10000, rng)) queue.push(x);
  int steps = 0;
  const auto all = [](const Entry&) { return true; };
  EXPECT_TRUE(detail::run_collapses(queue, nullptr, [&] { return steps < 100; }, all, [&](const Entry&) { ++steps; }));
  EXPECT_EQ(steps, 100);
  std::atomic<bool> cancel{true};
  EXPECT_FALSE(detail::run_collapses(queue, &cancel, [] { return true; }, all, [&](const Entry&) { ++steps; }));
  EXPECT_EQ(steps, 100);  // the flag is looked at before the first entry
  cancel = false;
  EXPECT_TRUE(detail::run_collapses(queue, &cancel, [] { return true; }, all, [&](const Entry&) { ++steps; }));
  EXPECT_EQ(steps, 10000);
}

TEST(IncidenceLists, GrowRemoveAndKeepOrderLikeVectors) {
  std::mt19937 rng(5);
  const int n = 50;
  detail::IncidenceLists lists;
  detail::Arena arena;
  lists.reserve(std::vector<int32_t>(n, 2));
  std::vector<std::vector<int32_t>> reference(n);
  std::uniform_int_distribution<int> vertex(0, n - 1), op(0, 9);
  for (int i = 0; i < 20000; ++i) {
    const int v = vertex(rng);
    if (op(rng) < 7 || reference[v].empty()) {
      lists.push_back(v, i, arena);
      reference[v].push_back(i);
    } else if (op(rng) < 9) {
      const int32_t f = reference[v][std::uniform_int_distribution<size_t>(0, reference[v].size() - 1)(rng)];
      lists.erase(v, f);
      reference[v].erase(std::find(reference[v].begin(), reference[v].end(), f));
    } else {
      lists.clear(v);
      reference[v].clear();
    }
  }
  for (int v = 0; v < n; ++v) {
    const auto got = lists[v];
    EXPECT_EQ(std::vector<int32_t>(got.begin(), got.end()), reference[v]) << "vertex " << v;
  }
}

TEST(ColorQuadrics, ThreadSplitSumsEqualOneSerialLoopBitForBit) {
  // Enough colors for several ranges (one per 4096 values), faces with random corners.
  std::mt19937 rng(9);
  const int nc = 20000, nf = 30000;
  std::uniform_int_distribution<int32_t> color(0, nc - 1);
  std::uniform_real_distribution<double> coord(0, 100), value(0, 1);
  std::vector<std::array<int32_t, 3>> corners(nf);
  std::vector<std::array<detail::Point5, 3>> points(nf);
  for (int f = 0; f < nf; ++f) {
    for (int k = 0; k < 3; ++k) {
      corners[f][k] = color(rng);
      points[f][k] = {coord(rng), coord(rng), value(rng), value(rng), value(rng)};
    }
  }
  std::vector<detail::Quadric5> serial(nc);
  for (int f = 0; f < nf; ++f) {
    const detail::Quadric5 q = detail::plane_quadric(points[f][0], points[f][1], points[f][2]);
    for (int k = 0; k < 3; ++k) serial[corners[f][k]] += q;
  }
  for (int threads : {1, 2, 5}) {
    const std::vector<detail::Quadric5> got =
        detail::color_quadrics(nf, nc, threads, [&](int f, int k, detail::Point5& p) {
          p = points[f][k];
          return corners[f][k];
        });
    ASSERT_EQ(got.size(), serial.size());
    for (int c = 0; c < nc; ++c) {
      ASSERT_EQ(got[c].a, serial[c].a) << "color " << c << ", " << threads << " threads";
      ASSERT_EQ(got[c].b, serial[c].b);
      ASSERT_EQ(got[c].c, serial[c].c);
    }
  }
}

}  // namespace
}  // namespace subvec
