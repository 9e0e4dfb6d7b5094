"""Shared start of terracut's plot scripts: error exits, the numpy/matplotlib
imports (Debian's python3-numpy and python3-matplotlib), and the
`SCRIPT DIR [--out FILE.png] [--quiet]` command line."""
import os
import sys


def make_fail(script):
    """A fail(message, code=2) that prints 'SCRIPT: error: message' and exits."""

    def fail(message, code=2):
        print(f"{script}: error: {message}", file=sys.stderr)
        sys.exit(code)

    return fail


def save_figure(fig, out, fail, quiet, script):
    """Writes fig to out (exit code 2 naming the file when it cannot) and
    says so unless quiet."""
    fig.tight_layout()
    try:
        fig.savefig(out, dpi=100)
    except OSError as e:
        fail(f"{out}: cannot write the figure: {e}")
    if not quiet:
        print(f"{script}: wrote {out}")


def import_plotting(fail):
    """(numpy, matplotlib.pyplot) with the Agg backend; exit code 3 when missing."""
    try:
        import numpy
    except ImportError:
        fail("missing Python module 'numpy' (Debian: apt-get install python3-numpy)", 3)
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot
    except ImportError:
        fail("missing Python module 'matplotlib' (Debian: apt-get install python3-matplotlib)", 3)
    return numpy, matplotlib.pyplot


def _parse_args(argv, doc, fail):
    """(folders, --out value or None, quiet) from argv; --help prints doc and exits 0."""
    folders, out, quiet = [], None, False
    i = 1
    while i < len(argv):
        a = argv[i]
        if a in ("-h", "--help"):
            print(doc)
            sys.exit(0)
        elif a == "--quiet":
            quiet = True
        elif a == "--out":
            if i + 1 >= len(argv):
                fail("--out needs a file name")
            out = argv[i + 1]
            i += 1
        else:
            folders.append(a)
        i += 1
    return folders, out, quiet


def parse_out_args(argv, doc, default_png, fail):
    """(output png, quiet) from `SCRIPT [--out FILE.png] [--quiet]`."""
    folders, out, quiet = _parse_args(argv, doc, fail)
    if folders:
        fail(f"unknown argument {folders[0]!r} (see --help)")
    return out or default_png, quiet


def import_terracut(fail):
    """The terracut module; exit code 3 when it is missing."""
    try:
        import terracut
    except ImportError:
        fail("missing Python module 'terracut' (build it, then PYTHONPATH=build/python)", 3)
    return terracut


def parse_dir_args(argv, doc, default_png, fail, script):
    """(folder, output png, quiet) from `SCRIPT DIR [--out FILE.png] [--quiet]`."""
    folders, out, quiet = _parse_args(argv, doc, fail)
    if not folders:
        fail(f"no output folder given (usage: {script} DIR [--out FILE.png])")
    if len(folders) > 1:
        fail(f"unexpected argument '{folders[1]}' (see --help)")
    return folders[0], out or os.path.join(folders[0], default_png), quiet


def parse_dirs_args(argv, doc, fail, script):
    """(folders, output png, quiet) from `SCRIPT --out FILE.png DIR [DIR ...] [--quiet]`."""
    folders, out, quiet = _parse_args(argv, doc, fail)
    if out is None or not folders:
        fail(f"usage: {script} --out FILE.png DIR [DIR ...]")
    return folders, out, quiet


def over_seeds(np, rows, key, scale=1.0):
    """Per round trip of a `terracut mmt --sweep` study.csv's rows: (rtts,
    mean, distance down to the best seed, up to the worst) of column key
    times scale, leaving out the runs that have no figure (negative: no cut
    in the window)."""
    rtts, mean, down, up = [], [], [], []
    for r in sorted(set(rows["rtt_ms"])):
        v = rows[key][(rows["rtt_ms"] == r) & (rows[key] >= 0)] * scale
        if len(v) == 0:
            continue
        rtts.append(r)
        mean.append(v.mean())
        down.append(max(v.mean() - v.min(), 0.0))
        up.append(max(v.max() - v.mean(), 0.0))
    return rtts, np.array(mean), np.array(down), np.array(up)


def parse_folder_args(argv, doc):
    """(folder, quiet) from `SCRIPT DIR [--quiet]`, for the scripts that draw a
    report folder's figures into it; --help prints doc and exits 0, any other
    command line prints it and exits 2."""
    args = [a for a in argv[1:] if a != "--quiet"]
    quiet = len(args) != len(argv) - 1
    if len(args) != 1 or args[0] in ("-h", "--help"):
        print(doc)
        sys.exit(0 if args in (["-h"], ["--help"]) else 2)
    return args[0], quiet


class FigureFolder:
    """The data files and figures of a report folder written by `command`
    (e.g. "terracut reproduce"): CSV and .npy files read with numpy (a missing
    one is fail()ed, naming the command that writes it) and figures saved at
    one DPI, each saying where it went unless quiet."""

    def __init__(self, np, plt, fail, script, command, dpi):
        self.np, self.plt, self.fail = np, plt, fail
        self.script, self.command, self.dpi = script, command, dpi
        self.quiet = False

    def read_meta(self, folder, name):
        """The JSON file `name` the command wrote into folder."""
        import json

        path = os.path.join(folder, name)
        if not os.path.isfile(path):
            self.fail(f"{path} not found (run `{self.command} --out {folder}` first)")
        with open(path, encoding="utf-8") as f:
            return json.load(f)

    def read_csv(self, path):
        """A CSV file with a header row, as a numpy structured array."""
        if not os.path.isfile(path):
            self.fail(f"{path} not found (run `{self.command} --out DIR` first)")
        return self.np.genfromtxt(path, delimiter=",", names=True, dtype=None, encoding="utf-8")

    def read_npy(self, path):
        if not os.path.isfile(path):
            self.fail(f"{path} not found")
        return self.np.load(path)

    def save(self, fig, folder, name, title=None):
        """Writes fig to folder/name; with a title, as its suptitle, laid out first."""
        if title is not None:
            fig.suptitle(title)
            fig.tight_layout()
        path = os.path.join(folder, name)
        fig.savefig(path, dpi=self.dpi)
        self.plt.close(fig)
        if not self.quiet:
            print(f"{self.script}: wrote {path}")
