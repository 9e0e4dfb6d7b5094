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


def parse_dir_args(argv, doc, default_png, fail, script):
    """(folder, output png, quiet) from `SCRIPT DIR [--out FILE.png] [--quiet]`."""
    folder, out, quiet = None, None, False
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
        elif folder is None:
            folder = a
        else:
            fail(f"unexpected argument '{a}' (see --help)")
        i += 1
    if folder is None:
        fail(f"no output folder given (usage: {script} DIR [--out FILE.png])")
    return folder, out or os.path.join(folder, default_png), quiet
