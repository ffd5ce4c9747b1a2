"""Plot particle-steps per second against N from a `tidem bench --out FILE.json` run.

    python benchmarks/plot_scale.py benchmarks/scale.json benchmarks/scale.png
"""

import json
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main(src: str, dst: str) -> None:
    rows = json.load(open(src))
    fig, ax = plt.subplots(figsize=(6, 4), dpi=120)
    for prec, marker in (("float32", "o"), ("float64", "s")):
        pts = sorted((r["particles"], r["particle_steps_per_s"]) for r in rows if r["precision"] == prec)
        if pts:
            ax.plot(*zip(*pts), marker=marker, label=prec)
    ax.set_xscale("log")
    ax.set_xlabel("particles N")
    ax.set_ylabel("particle-steps per second")
    ax.set_ylim(bottom=0)
    ax.set_title("tidem bench, settled bed, 2 threads")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(dst)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
