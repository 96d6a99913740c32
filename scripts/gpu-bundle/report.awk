# The GPU check's tables and targets (Markdown) from subvec_bench's JSON output (run, in the
# bundle): awk -f report.awk bench.json. Google Benchmark writes one "key": value per line, so a
# benchmark is the lines from its "name" to the next one. Medians where there are repetitions.

function value(line) {  # the value of a "key": value line, without quotes and the trailing comma
  sub(/^[^:]*:[ ]*/, "", line)
  sub(/,[ ]*$/, "", line)
  gsub(/^"|"$/, "", line)
  return line
}
function ms(x, unit) {  # a time in milliseconds
  if (unit == "ns") return x / 1e6
  if (unit == "us") return x / 1e3
  if (unit == "s") return x * 1e3
  return x + 0
}
function show(x) {  # a time: three significant digits
  if (x == "" || tolower(x) ~ /nan/) return "–"
  x += 0
  if (x >= 100) return sprintf("%.0f", x)
  if (x >= 10) return sprintf("%.1f", x)
  if (x >= 1) return sprintf("%.2f", x)
  return sprintf("%.3f", x)
}
function keep(   base, pref) {
  if (name == "") return
  base = name
  pref = 1                                      # a single run (one repetition)
  if (aggregate != "") {
    if (aggregate != "median") return
    sub(/_median$/, "", base)
    pref = 2
  }
  sub(/\/real_time$/, "", base)
  if ((base in rank) && rank[base] > pref) return
  rank[base] = pref
  if (error != "") { err[base] = error; return }
  time[base] = ms(real, unit)
  for (k in counter) c[base, k] = counter[k]
}

/"benchmarks": \[/ { inside = 1; next }
!inside { next }
/^ *"name":/ {
  keep()
  name = value($0); aggregate = ""; error = ""; real = ""; unit = "ns"
  delete counter
  next
}
/^ *"aggregate_name":/ { aggregate = value($0); next }
/^ *"error_message":/ { error = value($0); next }
/^ *"real_time":/ { real = value($0); next }
/^ *"time_unit":/ { unit = value($0); next }
/^ *"(mae|max_diff|control_vertices|[a-z_]+_ms)":/ {
  key = $0; sub(/^ *"/, "", key); sub(/".*/, "", key)
  counter[key] = value($0)
  next
}
END {
  keep()
  nimages = split("3k 20k", images, " ")
  nsizes = split("512x512 1920x1080 3840x2160", sizes, " ")
  nkinds = split("cached edit", kinds, " ")
  label["cached"] = "cached"; label["edit"] = "after an edit"

  print "## Frame times"
  print ""
  print "Median milliseconds per frame, read-back into the caller's image included (`GpuFrame`, `CpuFrame`)."
  print ""
  table_head("renderer|image|frame", nsizes, sizes)
  nr = split("GpuFrame CpuFrame", renderers, " ")
  for (r = 1; r <= nr; ++r) {
    for (i = 1; i <= nimages; ++i) for (k = 1; k <= nkinds; ++k) {
      printf "| %s | %s | %s |", (renderers[r] == "GpuFrame" ? "GPU" : "CPU"), images[i], label[kinds[k]]
      for (s = 1; s <= nsizes; ++s) {
        b = renderers[r] "/" images[i] "/" sizes[s] "/" kinds[k]
        printf " %s |", (b in err) ? "skipped: " err[b] : (b in time) ? show(time[b]) : "–"
      }
      print ""
    }
  }
  print ""
  print "## GPU against the CPU renderer"
  print ""
  print "The frames above, compared after timing: mean absolute difference over the channel values, and the largest."
  print ""
  table_head("image|frame", nsizes, sizes)
  worst_mae = -1; worst_max = -1
  for (i = 1; i <= nimages; ++i) for (k = 1; k <= nkinds; ++k) {
    printf "| %s | %s |", images[i], label[kinds[k]]
    for (s = 1; s <= nsizes; ++s) {
      b = "GpuFrame/" images[i] "/" sizes[s] "/" kinds[k]
      if ((b, "mae") in c) {
        printf " MAE %.4f, max %d |", c[b, "mae"], c[b, "max_diff"]
        if (c[b, "mae"] + 0 > worst_mae) worst_mae = c[b, "mae"] + 0
        if (c[b, "max_diff"] + 0 > worst_max) worst_max = c[b, "max_diff"] + 0
      } else printf " – |"
    }
    print ""
  }
  print ""
  print "## Where a GPU frame's time goes"
  print ""
  print "`GpuPasses`: the GPU frames again, each pass timed by GL timer queries (GPU time, ms per frame,"
  print "summed over tiles); read-back and frame are wall-clock. The queries make each frame wait for the"
  print "GPU, so these frames are slower than the `GpuFrame` ones. – : no time, or one the driver got"
  print "wrong (longer than the wall time since the pass was issued)."
  if (software) {
    print ""
    print "**This is a software rasterizer:** llvmpipe defers draws and runs compute shaders at once, so"
    print "its timer queries do not follow the passes' work, and these times mean little."
  }
  print ""
  npasses = split("stencils centres samples mark resolve read_back frame", passes, " ")
  for (p = 1; p <= npasses; ++p) names[p] = passes[p]
  names[6] = "read-back (wall)"; names[7] = "whole frame (wall)"
  table_head("image|size|frames", npasses, names)
  for (i = 1; i <= nimages; ++i) for (s = 1; s <= nsizes; ++s) for (k = 1; k <= nkinds; ++k) {
    b = "GpuPasses/" images[i] "/" sizes[s] "/" kinds[k]
    if (!(b in time) && !(b in err)) continue
    printf "| %s | %s | %s |", images[i], sizes[s], label[kinds[k]]
    for (p = 1; p <= npasses; ++p) {
      if (b in err) printf " %s |", (p == 1 ? "skipped: " err[b] : "")
      else printf " %s |", ((b, passes[p] "_ms") in c) ? show(c[b, passes[p] "_ms"]) : "–"
    }
    print ""
  }
  print ""
  print "## Targets (issue 27)"
  print ""
  print "| target | measured | |"
  print "|---|---|---|"
  target("4K frame, 3k vertices, cached", "GpuFrame/3k/3840x2160/cached", 1)
  target("512x512 frame, 3k vertices, cached", "GpuFrame/3k/512x512/cached", 0.2)
  target("4K color and position edit + redraw, 3k vertices", "GpuFrame/3k/3840x2160/edit", 2)
  if (worst_mae < 0) print "| GPU = CPU within MAE 0.5, max 8 | not measured | |"
  else printf "| GPU = CPU within MAE 0.5, max 8 | worst MAE %.4f, worst max %d | %s |\n", worst_mae, worst_max, (worst_mae <= 0.5 && worst_max <= 8) ? "met" : "MISSED"
}
function table_head(first, n, names,   i, m, cols) {  # "a|b", then the names: the two header lines
  m = split(first, cols, "|")
  for (i = 1; i <= m; ++i) printf "| %s ", cols[i]
  for (i = 1; i <= n; ++i) printf "| %s ", names[i]
  print "|"
  for (i = 1; i <= m + n; ++i) printf "|---"
  print "|"
}
function target(what, b, bound,   p, gpu) {
  if (b in err) { printf "| %s ≤ %s ms | skipped: %s | |\n", what, bound, err[b]; return }
  if (!(b in time)) { printf "| %s ≤ %s ms | not measured | |\n", what, bound; return }
  printf "| %s ≤ %s ms | %s ms | %s |\n", what, bound, show(time[b]), (time[b] <= bound) ? "met" : "MISSED"
  p = b; sub(/^GpuFrame/, "GpuPasses", p)
  if (time[b] > bound && (p, "frame_ms") in c) {
    gpu = c[p, "stencils_ms"] + c[p, "centres_ms"] + c[p, "samples_ms"] + c[p, "mark_ms"] + c[p, "resolve_ms"]
    if (c[p, "stencils_ms"] c[p, "centres_ms"] c[p, "samples_ms"] c[p, "mark_ms"] c[p, "resolve_ms"] ~ /[Nn][Aa][Nn]/) gpu = "nan"
    printf "| ↳ where it goes | GPU passes %s ms (stencils %s, centres %s, 4x4 samples %s, mark %s, resolve %s), read-back %s ms | |\n", show(gpu), show(c[p, "stencils_ms"]), show(c[p, "centres_ms"]), show(c[p, "samples_ms"]), show(c[p, "mark_ms"]), show(c[p, "resolve_ms"]), show(c[p, "read_back_ms"])
  }
}
