#!/usr/bin/env python3
"""Benchmark of the bake (soup + octree + LOD hierarchy + node files; seed 3.4, 3.5.3, 4.3,
Table 5.1).

Generates sample inputs with `octolod sample` (cached in the work directory), runs
`octolod --json bake` under /usr/bin/time -v, and prints per-stage seconds (soup, octree sort,
octree stream with the node work overlapping, the LOD work left after the stream, the node work
summed over threads), triangles/s and peak RSS (from the kernel, after the process ended: the
manifest writing is included; also minus the RSS of an idle `octolod --help`, the CLI's fixed
footprint of shared libraries, and whether the whole process stayed within --memory, which
covers that footprint), for the full bake and for `--method none` (soup + octree +
leaf files only), then the seed's Table 5.1: leaves and build time against max-tris 1000..6000 at
depths 5 and 8 (octree only by default, --table-method grid for the full bake).

Also user and system CPU seconds and the MiB the process wrote (the kernel's count).

  bench/bake_bench.py --cli build/cli/octolod [--work /tmp/bake-bench] [--sizes 1M,10M]
                      [--memory 48M,64M,256M] [--threads 2] [--methods grid,none]
                      [--table-size 1M] [--table-method none] [--no-table] [--markdown]
--markdown prints the tables as Markdown (for docs/benchmarks.md).
"""
import argparse
import json
import os
import re
import shutil
import subprocess
import sys


def idle_rss_mib(cli):
    p = subprocess.run(["/usr/bin/time", "-v", cli, "--help"], capture_output=True, text=True)
    return int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", p.stderr).group(1)) / 1024.0


def run_bake(cli, ply, out, work, memory, threads, max_tris=2000, max_depth=10, method="grid"):
    shutil.rmtree(out, ignore_errors=True)
    cmd = ["/usr/bin/time", "-v", cli, "--json", "bake", ply, "-o", out, "--work-dir", work,
           "--memory", memory, "--threads", str(threads), "--max-tris", str(max_tris),
           "--max-depth", str(max_depth), "--method", method]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit("bake failed: %s\n%s" % (" ".join(cmd), p.stderr))
    report = json.loads(p.stdout)
    rss_kib = int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", p.stderr).group(1))
    wall = re.search(r"Elapsed \(wall clock\) time \(h:mm:ss or m:ss\): ([\d:.]+)", p.stderr).group(1)
    parts = [float(x) for x in wall.split(":")]
    seconds = sum(v * 60 ** (len(parts) - 1 - i) for i, v in enumerate(parts))
    report["process_peak_rss_mib"] = rss_kib / 1024.0
    report["process_seconds"] = seconds
    report["process_user_seconds"] = float(re.search(r"User time \(seconds\): ([\d.]+)", p.stderr).group(1))
    report["process_sys_seconds"] = float(re.search(r"System time \(seconds\): ([\d.]+)", p.stderr).group(1))
    # "File system outputs" counts 512-byte blocks written.
    report["process_written_mib"] = int(re.search(r"File system outputs: (\d+)", p.stderr).group(1)) / 2048.0
    shutil.rmtree(out, ignore_errors=True)
    return report


def parse_count(text):
    scale = {"K": 1e3, "M": 1e6, "G": 1e9}.get(text[-1].upper(), 1)
    return int(float(text.rstrip("KMGkmg")) * scale)


def mib(text):
    scale = {"K": 1 / 1024, "M": 1, "G": 1024}.get(text[-1].upper(), 1 / 2 ** 20)
    return float(text.rstrip("KMGkmg")) * scale


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--cli", required=True)
    ap.add_argument("--work", default="/tmp/bake-bench")
    ap.add_argument("--sizes", default="1M,10M")
    ap.add_argument("--memory", default="48M,64M,256M")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--methods", default="grid,none")
    ap.add_argument("--table-size", default="1M")
    ap.add_argument("--table-method", default="none",
                    help="--method of the Table 5.1 bakes (none: the octree build the seed times)")
    ap.add_argument("--no-table", action="store_true")
    ap.add_argument("--markdown", action="store_true")
    args = ap.parse_args()
    os.makedirs(args.work, exist_ok=True)
    work_tmp = os.path.join(args.work, "tmp")
    os.makedirs(work_tmp, exist_ok=True)
    out = os.path.join(args.work, "out")

    def sample(size):
        ply = os.path.join(args.work, "rock-%s.ply" % size)
        if not os.path.exists(ply):
            subprocess.run([args.cli, "sample", "--shape", "rock", "--triangles", size, "-o", ply],
                           check=True, capture_output=True)
        return ply

    sep = "|" if args.markdown else " "
    def row(cells):
        line = sep.join(str(c) for c in cells)
        print(("| " + " | ".join(str(c) for c in cells) + " |") if args.markdown else line)

    print("load average at start: %.2f %.2f %.2f" % os.getloadavg())
    idle = idle_rss_mib(args.cli)
    print("idle `octolod --help` peak RSS: %.1f MiB" % idle)
    header = ["triangles", "method", "memory", "soup path", "soup s", "octree sort s",
              "octree stream s", "lods after stream s", "node work s", "total s", "wall s",
              "user s", "sys s", "written MiB", "M tri/s", "nodes", "LODs", "root coarsest tris", "sort runs", "LOD rereads",
              "streamed internal nodes",
              "peak RSS MiB", "RSS - idle MiB", "RSS before manifest - idle MiB",
              "within --memory"]
    row(header)
    if args.markdown:
        row(["---"] * len(header))
    for size in args.sizes.split(","):
        ply = sample(size)
        for method in args.methods.split(","):
            for memory in args.memory.split(","):
                r = run_bake(args.cli, ply, out, work_tmp, memory, args.threads, method=method)
                s = r["stage_seconds"]
                st = r["stats"]
                rss = r["process_peak_rss_mib"]
                path = "out of core"
                if r["soup_in_core"]:
                    path = "in core, octree in memory" if st.get("octree_in_memory") else "in core"
                row([size, method, memory, path,
                     "%.2f" % s["soup"], "%.2f" % s["octree.sort"], "%.2f" % s["octree.stream"],
                     "%.2f" % s.get("lods", 0), "%.2f" % st.get("node_work_seconds", 0),
                     "%.2f" % s["total"], "%.2f" % r["process_seconds"],
                     "%.2f" % r["process_user_seconds"], "%.2f" % r["process_sys_seconds"],
                     "%.0f" % r["process_written_mib"],
                     "%.2f" % (r["triangles"] / s["total"] / 1e6), r["nodes"], r["lods"],
                     r["root_coarsest_triangles"], r["octree_sort_runs"],
                     int(st.get("lod_rereads", 0)), int(st.get("lod_streamed_internal_nodes", 0)),
                     "%.1f" % rss, "%.1f" % (rss - idle),
                     "%.1f" % (r["peak_rss_bytes"] / 2.0 ** 20 - idle),
                     "yes" if rss <= mib(memory) else "NO"])
                sys.stdout.flush()

    if args.no_table:
        return
    print()
    ply = sample(args.table_size)
    header = ["max-tris"] + ["depth %d leaves" % d for d in (5, 8)] + \
             ["depth %d seconds" % d for d in (5, 8)]
    row(header)
    if args.markdown:
        row(["---"] * len(header))
    for max_tris in range(1000, 7000, 1000):
        cells = {}
        for depth in (5, 8):
            # with LODs, leaves of 6000 triangles need more than 64M (the bake's node work)
            memory = "64M" if args.table_method == "none" else "256M"
            r = run_bake(args.cli, ply, out, work_tmp, memory, args.threads, max_tris, depth,
                         args.table_method)
            cells[depth] = r
        row([max_tris, cells[5]["leaves"], cells[8]["leaves"],
             "%.2f" % cells[5]["stage_seconds"]["total"],
             "%.2f" % cells[8]["stage_seconds"]["total"]])
        sys.stdout.flush()


if __name__ == "__main__":
    main()
