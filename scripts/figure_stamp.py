"""Writes a figure marked with the Fountain commit it was made from: a small note in its
lower right corner and, in a PNG, the Source text field, so that every figure in docs/ can be
traced to the code that drew it (and a figure left behind by newer code shows its age).

    sys.path.insert(0, "<repo>/scripts"); from figure_stamp import save
    save(fig, "out.png", dpi=110)

The commit is `git describe --always --dirty` of the repository holding this file (a tree with
uncommitted changes shows "-dirty"); FOUNTAIN_COMMIT overrides it, e.g. for figures of runs
made by an older binary.
"""
import os
import subprocess

_REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def fountain_commit():
    if os.environ.get("FOUNTAIN_COMMIT"):
        return os.environ["FOUNTAIN_COMMIT"]
    try:
        out = subprocess.run(["git", "-C", _REPO, "describe", "--always", "--dirty", "--abbrev=12"],
                             capture_output=True, text=True, check=True)
        return out.stdout.strip() or "unknown"
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def save(fig, path, **kwargs):
    commit = fountain_commit()
    fig.text(0.995, 0.004, f"Fountain {commit}", ha="right", va="bottom", fontsize=6, color="0.45")
    metadata = {"Source": f"Fountain {commit}"} if str(path).lower().endswith(".png") else None
    fig.savefig(path, metadata=metadata, **kwargs)
