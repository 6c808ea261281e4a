"""Benchmark outputs: JSON report, printed table, log-log throughput plot, RESULTS.md."""

from __future__ import annotations

import json
from pathlib import Path

from bench.markdown import cell, header, section, write_markdown, write_result

BYTES = {"float64": 8, "float32": 4}


def _atomic_write(path: Path, text: str) -> None:
    from jaxspline.planner.files import atomic_write_text

    atomic_write_text(path, text)


def _limit(report, k) -> float | None:
    """Streaming limit in candidates/s for a kernel row: bandwidth / bytes moved per candidate."""
    bw = report.get("bandwidth", {}).get("GBps")
    if not bw:
        return None
    from bench.cases import workloads

    w = {w.name: w for w in workloads()}[k["workload"]]
    nbytes = len(w.args) * BYTES[k["dtype"]] + w.out_bytes * (
        1 if w.out_bytes == 1 else BYTES[k["dtype"]] // 8
    )
    return bw * 1e9 / nbytes


def table(report) -> str:
    """Markdown table of the headline figures."""
    lines = []
    if "bandwidth" in report:
        lines.append(
            f"Streaming limit (jnp.sum over {report['bandwidth']['bytes'] / 2**30:.1f} GiB): "
            f"**{report['bandwidth']['GBps']:.1f} GB/s**\n"
        )
    if report.get("kernels"):
        lines += [
            "| kernel | dtype | best batch | JAX cand/s at best (spread) | largest batch | "
            "JAX cand/s at largest | % of streaming limit (largest) | compile s | "
            "numpy cand/s | JAX/numpy (same batch) | Python cand/s | JAX/Python | "
            "Ruckig cand/s | JAX/Ruckig |",
            "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
        ]
        for k in report["kernels"]:
            best = max(k["jax"], key=lambda r: r["rate"])
            last = k["jax"][-1]
            lim = _limit(report, k)
            cells = [
                k["workload"],
                k["dtype"],
                f"{best['n']:.0e}",
                f"{best['rate']:.3g} ({best['rate_lo']:.3g}–{best['rate_hi']:.3g})",
                f"{last['n']:.2g}",
                f"{last['rate']:.3g}",
                f"{100 * last['rate'] / lim:.0f}%" if lim else "–",
                f"{k['jax'][0]['compile_s']:.2f}",
            ]
            for key in ("numpy", "python", "ruckig"):
                b = k.get(key)
                if not b:
                    cells += ["–", "–"]
                    continue
                # compare at the baseline's own batch size where JAX was measured there
                same = [r for r in k["jax"] if r["n"] == b.get("n")]
                ref = same[0] if (key == "numpy" and same) else best
                cells += [f"{b['rate']:.3g}", f"{ref['rate'] / b['rate']:.0f}×"]
            lines.append("| " + " | ".join(cells) + " |")
    for k in report.get("kernels", []):
        ns = k.get("numpy_streamed")
        if ns:
            lines.append(
                f"\n{k['workload']} ({k['dtype']}) streamed from memory ({ns['n']:.3g} "
                f"materialized candidates): numpy {ns['rate']:.3g} cand/s vs JAX "
                f"{ns['jax_rate']:.3g} cand/s: JAX/numpy {ns['jax_rate'] / ns['rate']:.0f}×"
            )
    lean = [k for k in report.get("kernels", []) if "numpy_lean" in k]
    for k in lean:
        same = [r for r in k["jax"] if r["n"] == k["numpy_lean"]["n"]]
        if same:
            lines.append(
                f"\n{k['workload']} ({k['dtype']}) against a leaner hand-written numpy formula "
                f"(no tolerance handling): {k['numpy_lean']['rate']:.3g} cand/s, "
                f"JAX/numpy_lean {same[0]['rate'] / k['numpy_lean']['rate']:.0f}×"
            )
    if "threads" in report:
        t = report["threads"]
        lines.append(
            f"\nMembership, float64, n = {t['n']:.0e}: "
            + ", ".join(
                f"{k.replace('_', ' ')} {v['rate']:.3g}/s"
                for k, v in t.items()
                if isinstance(v, dict) and "rate" in v
            )
        )
    return "\n".join(lines)


#: Columns of the speed table of ``SCREENING.md``.
SPEED_COLUMNS = (
    "routes|options|mode|candidates|feasible|rows returned|host cand/s|fused cand/s|"
    "fused/host|ceiling cand/s|fused/ceiling|same rows as host|fused float32 cand/s|"
    "first call s host / fused"
).split("|")
#: Columns of the memory table of ``SCREENING.md``.
RSS_COLUMNS = (
    "routes|path|mode|candidates|rows returned|result MB|RSS before MB|peak RSS MB|"
    "s (incl. compile)"
).split("|")
#: Columns of the screen-and-search table of ``SCREENING.md``.
STREAM_COLUMNS = (
    "routes|screen -> search|candidates|rows streamed|plan options|value|RSS before MB|"
    "peak RSS MB|s (incl. compile)|cand/s"
).split("|")


def _speed_rows(sc) -> list[str]:
    lines = []
    for s in sc.get("speed", []):
        for m in s["modes"]:
            r, first = m["rate"], m.get("first_s", {})
            feas = m["n_feasible"] / m["n_screened"] if m.get("n_feasible") is not None else None
            lines.append(
                f"| {s['routes']} | {s['options']} | {m['mode']} | "
                f"{m['n_screened']:.3g} | {cell(feas, '{:.0%}')} | "
                f"{m['rows']:.3g} | {r['host']:.3g} | {r['fused']:.3g} | "
                f"{m['fused_over_host']:.2f}× | {r['ceiling']:.3g} | "
                f"{m['fused_over_ceiling']:.0%} | {cell(m['identical_to_host'])} | "
                f"{cell(r.get('fused_float32'))} | "
                f"{cell(first.get('host'), '{:.1f}')} / {cell(first.get('fused'), '{:.1f}')} |"
            )
    return lines


def _rss_rows(sc) -> list[str]:
    lines = []
    for m in sc.get("rss", []):
        head = f"| {m['routes']} | {m['path']} | {m['mode']} |"
        if "skipped" in m:
            lines.append(f"{head} {m['candidates']:.3g} | not run: {m['skipped']} | | | | |")
        elif "error" in m:
            lines.append(f"{head} failed: {m['error'][-60:]!r} | | | | | |")
        else:
            lines.append(
                f"{head} {m['n_screened']:.3g} | {m['rows']:.3g} | {m['result_MB']:.0f} | "
                f"{m['rss_before_MB']:.0f} | {m['peak_MB']:.0f} | "
                f"{m['seconds_incl_compile']:.1f} |"
            )
    return lines


def _stream_rows(sc) -> list[str]:
    lines = []
    for m in sc.get("stream", []):
        what = "all feasible -> greedy" if m["search"] == "greedy" else "top-k -> beam"
        if "error" in m:
            lines.append(f"| {m['routes']} | {what} | failed: {m['error'][-60:]!r} |||||||")
            continue
        lines.append(
            f"| {m['routes']} | {what} | {m['n_screened']:.3g} | {m['rows_streamed']:.3g} | "
            f"{m['plan_options']} | {m['value']:.1f} | {m['rss_before_MB']:.0f} | "
            f"{m['peak_MB']:.0f} | {m['seconds_incl_compile']:.1f} | {m['rate']:.3g} |"
        )
    return lines


def screening_table(sc) -> list[str]:
    """Markdown: speed (host vs fused vs ceiling, same run), peak RSS per call, and the
    streamed screen + search, each table in its snippet section."""
    from bench.scenarios import BEAM_WIDTH, MAX_GAP, TOP_K

    return [
        "\nWorkload: `bench.scenarios.synthetic_options(ROUTES)`, one synthetic pass, every "
        f"transition within {MAX_GAP:g} s screened, float64. *host* is the reference path "
        "(`jaxspline/screen/host.py`: pairs built on the host per chunk, masked and "
        "concatenated there), *fused* the default (`jaxspline/screen/fused.py`: pairs "
        "generated from the time-sorted option table inside the compiled program, every "
        "channel's exact-T test and the margin in one pass, rows compacted on the device), "
        "*ceiling* the same per-candidate kernels on candidates already materialized on the "
        "device (no pair generation, compaction or copies out). Modes: *all* rows, "
        "*feasible* rows only (`feasible_only=True`), *top_k* (the "
        f"{TOP_K} feasible successors of largest margin per option). Speed: one process "
        "per route count, interleaved repetitions, medians after compilation; *first call* "
        "includes compilation.",
        *section("speed", [*header(*SPEED_COLUMNS), *_speed_rows(sc)]),
        "\nMemory: one fresh process per row, peak resident set (`VmHWM`) of one call, "
        "compilation included, after the options are built (MB of 1e6 bytes).",
        *section("memory", [*header(*RSS_COLUMNS), *_rss_rows(sc)]),
        "\nScreen and search in one pass: `screen_chunks` feeds its chunks to the sequencer "
        "as they come off the device, so nothing of the size of the candidates is held "
        "(one fresh process per row, compilation included). *greedy* takes every feasible "
        f"row, *beam* the {TOP_K} successors of largest value density per option with "
        f"beam width {BEAM_WIDTH}.",
        *section("stream", [*header(*STREAM_COLUMNS), *_stream_rows(sc)]),
    ]


def write_screening(report, out: Path) -> None:
    """Write ``screening.json`` and ``SCREENING.md`` into ``out`` and print the tables."""
    lines = screening_table(report["screening"])
    write_result(out, "screening", report, "Screening engine", lines)


def plot(report, path: Path) -> None:
    """Throughput vs batch size (log-log), one line per kernel and dtype, with limits/baselines."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(9, 6))
    colors = {}
    for k in report.get("kernels", []):
        c = colors.setdefault(k["workload"], f"C{len(colors)}")
        ns = [r["n"] for r in k["jax"]]
        ax.plot(
            ns,
            [r["rate"] for r in k["jax"]],
            "-o" if k["dtype"] == "float64" else "--s",
            color=c,
            ms=4,
            label=f"{k['workload']} ({k['dtype']})",
        )
        for key, mk in (("numpy", "x"), ("ruckig", "v"), ("python", "^")):
            if key in k:
                ax.plot(
                    [k[key]["n"] if key != "numpy" else 1e6],
                    [k[key]["rate"]],
                    mk,
                    color=c,
                    ms=8,
                    label=f"{k['workload']} {key}" if k["workload"] == "is_reachable" else None,
                )
    if "bandwidth" in report:
        lim = report["bandwidth"]["GBps"] * 1e9 / (5 * 8 + 1)
        ax.axhline(lim, color="k", lw=1, ls=":", label="streaming limit, membership f64")
    ax.set(
        xscale="log",
        yscale="log",
        xlabel="batch size (candidates)",
        ylabel="candidates / s (after compilation)",
        title="jaxspline kernels on CPU (x = numpy, ^ = pure Python, v = Ruckig)",
    )
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def results_lines(report) -> list[str]:
    """The body of ``RESULTS.md``: what was measured, then the tables (section ``kernels``)."""
    return [
        "\nKernels after compilation (compile time in its own column), median of the "
        "repetitions with the spread; batches above 2^20 candidates streamed in 2^20 chunks "
        "over a materialized pool far larger than the caches. Baselines on the same inputs: "
        "numpy running the kernel's own formula, a pure-Python loop and Ruckig per call, "
        "each compared with the JAX answers. The streaming limit is a jitted `jnp.sum` "
        "over the size given.\n",
        *section("kernels", [table(report)]),
    ]


def write_outputs(report, out: Path) -> None:
    """Write report.json, throughput.png, RESULTS.md into ``out`` and print the table."""
    _atomic_write(out / "report.json", json.dumps(report, indent=1, default=float))
    write_markdown(out / "RESULTS.md", "Kernel benchmark", results_lines(report))
    if report.get("kernels"):
        plot(report, out / "throughput.png")
    print(
        f"\nwrote {out}/report.json, RESULTS.md"
        + (", throughput.png" if report.get("kernels") else "")
        + f"  (total {report['total_s']:.0f} s)"
    )
