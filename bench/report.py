"""Benchmark outputs: JSON report, printed table, log-log throughput plot, RESULTS.md."""

from __future__ import annotations

import json
from pathlib import Path

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
    if report.get("screening"):
        lines += screening_table(report["screening"])
    return "\n".join(lines)


def _header(*cols: str) -> list[str]:
    """A markdown table's header and separator lines (after a blank line)."""
    return ["\n| " + " | ".join(cols) + " |", "|" + "---|" * len(cols)]


def screening_table(sc) -> list[str]:
    """Markdown rows: speed (host vs fused vs ceiling, same run), peak RSS per call, and
    the streamed screen + search."""
    lines = _header(
        "routes", "options", "mode", "candidates", "feasible", "rows returned", "host cand/s",
        "fused cand/s", "fused/host", "ceiling cand/s", "fused/ceiling", "same rows as host",
        "fused float32 cand/s",
    )  # fmt: skip
    for s in sc.get("speed", []):
        for m in s["modes"]:
            r = m["rate"]
            feas = m["n_feasible"] / m["n_screened"] if m.get("n_feasible") is not None else None
            lines.append(
                f"| {s['routes']} | {s['options']} | {m['mode']} | "
                f"{m['n_screened']:.3g} | {'–' if feas is None else f'{feas:.0%}'} | "
                f"{m['rows']:.3g} | {r['host']:.3g} | {r['fused']:.3g} | "
                f"{m['fused_over_host']:.2f}× | {r['ceiling']:.3g} | "
                f"{m['fused_over_ceiling']:.0%} | {m['identical_to_host']} | "
                f"{r.get('fused_float32', float('nan')):.3g} |"
            )
    lines += _header(
        "routes", "path", "mode", "candidates", "rows returned", "result MB", "RSS before MB",
        "peak RSS MB", "s (incl. compile)",
    )  # fmt: skip
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
    lines += _header(
        "routes", "screen -> search", "candidates", "rows streamed", "plan options", "value",
        "RSS before MB", "peak RSS MB", "s (incl. compile)", "cand/s",
    )  # fmt: skip
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


def write_outputs(report, out: Path) -> None:
    """Write report.json, throughput.png, RESULTS.md into ``out`` and print the table."""
    text = table(report)
    print("\n" + text)
    _atomic_write(out / "report.json", json.dumps(report, indent=1, default=float))
    _atomic_write(out / "RESULTS.md", text + "\n")
    if report.get("kernels"):
        plot(report, out / "throughput.png")
    print(
        f"\nwrote {out}/report.json, RESULTS.md"
        + (", throughput.png" if report.get("kernels") else "")
        + f"  (total {report['total_s']:.0f} s)"
    )
