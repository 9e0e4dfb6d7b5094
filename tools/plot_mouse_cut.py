#!/usr/bin/env python3
"""Plot the force of a mouse-driven cut before and after the viewer's target
ramp, in time and as a spectrum (docs/viewer.md).

Usage: plot_mouse_cut.py CSV [--out FILE.png]

CSV: columns t,before_n,after_n (seconds, newtons), one row per haptic tick,
as the test ViewerControls.AMouseDrivenCutDoesNotBuzzAtTheFrameRate writes
it when TERRACUT_MOUSE_CUT_CSV names a file:

  TERRACUT_MOUSE_CUT_CSV=/tmp/mouse_cut.csv build/tests/viewer/viewer_test \\
      --gtest_filter='ViewerControls.AMouse*'
  /usr/bin/python3 tools/plot_mouse_cut.py /tmp/mouse_cut.csv --out docs/images/mouse_cut_spectrum.png
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from plot_common import import_plotting, make_fail  # noqa: E402

SCRIPT = "plot_mouse_cut.py"
fail = make_fail(SCRIPT)


def main(argv):
    if len(argv) < 2 or argv[1] in ("-h", "--help"):
        print(__doc__)
        return 0 if len(argv) >= 2 else 2
    path, out = argv[1], None
    rest = argv[2:]
    while rest:
        if rest[0] == "--out" and len(rest) > 1:
            out, rest = rest[1], rest[2:]
        else:
            fail(f"unknown argument '{rest[0]}' (usage: {SCRIPT} CSV [--out FILE.png])")
    if out is None:
        out = os.path.splitext(path)[0] + ".png"
    np, plt = import_plotting(fail)
    if not os.path.isfile(path):
        fail(f"{path}: no such file")
    try:
        d = np.genfromtxt(path, delimiter=",", names=True)
    except ValueError as e:
        fail(f"{path}: not a CSV of t,before_n,after_n: {e}")
    for column in ("t", "before_n", "after_n"):
        if d.dtype.names is None or column not in d.dtype.names:
            fail(f"{path}: missing column '{column}' (expected t,before_n,after_n)")
    if d.size < 16:
        fail(f"{path}: {d.size} rows, at least 16 needed for a spectrum")
    t = d["t"]
    dt = float(np.median(np.diff(t)))
    fig, (ax_t, ax_f) = plt.subplots(1, 2, figsize=(11, 3.8))
    for name, label, colour in (("before_n", "lag alone (before)", "tab:red"),
                                ("after_n", "ramp over a frame + lag (after)", "tab:blue")):
        f = d[name]
        ax_t.plot(t, f, color=colour, lw=1.0, label=label)
        x = f - f.mean()
        amp = np.abs(np.fft.rfft(x * np.hanning(len(x)))) * 2.0 / (0.5 * len(x))
        freq = np.fft.rfftfreq(len(x), dt)
        ax_f.plot(freq[1:], np.maximum(amp[1:], 1e-6), color=colour, lw=1.0, label=label)
    ax_t.set_xlabel("time (s)")
    ax_t.set_ylabel("|horizontal force| (N, world)")
    ax_t.set_ylim(bottom=0.0)
    ax_t.set_title("force during a steady mouse-driven cut")
    ax_t.legend(fontsize=8, loc="lower right")
    ax_f.set_yscale("log")
    ax_f.set_xlim(0.0, 200.0)
    ax_f.set_xlabel("frequency (Hz)")
    ax_f.set_ylabel("amplitude (N)")
    ax_f.set_title("spectrum (frames at 25 Hz)")
    ax_f.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    print(f"{SCRIPT}: wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
