"""Many small files per process: one `nurbsrt render ... --out-dir` call against
one `nurbsrt render FILE -o` process per file, the same files, interleaved.

Makes N files with distinct bytes from small STEP models (each copy gets a
comment of its own after the header line, so no two files are equal and no
cache could serve one from another), then in each round times, in turn, the
loop of one process per file and one process for all of them. Prints the
median per-file cost of each and their ratio, with the machine's load.

Usage: python3 bench/many_files.py [path/to/nurbsrt]
Settings (environment): FILES (200), ROUNDS (3), SIZE (256), MODELS (space-
separated STEP files; default: the small STEP files of ../shared/models, else
OCCT's screw.step).
"""
import os
import pathlib
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parent.parent
# Small enough that the process's own set-up, not the file, is most of a lone
# render: the case a catalogue of many small parts is made of.
SMALL_BYTES = 100_000


def default_models():
    shared = ROOT.parent / "shared" / "models" / "step"
    found = sorted(p for p in shared.glob("*.st*p") if p.stat().st_size <= SMALL_BYTES) if shared.is_dir() else []
    return found or [pathlib.Path("/usr/share/opencascade/data/step/screw.step")]


def distinct_copies(models, n, out):
    """n STEP files, copies of `models` in turn, each with its own comment."""
    files = []
    for k in range(n):
        src = models[k % len(models)]
        text = src.read_bytes()
        cut = text.index(b";") + 1  # after ISO-10303-21;
        dst = out / f"{src.stem}-{k:04d}.step"
        dst.write_bytes(text[:cut] + f"\n/* copy {k} */".encode() + text[cut:])
        files.append(dst)
    return files


def main():
    exe = sys.argv[1] if len(sys.argv) > 1 else str(ROOT / "build" / "nurbsrt")
    n = int(os.environ.get("FILES", "200"))
    rounds = int(os.environ.get("ROUNDS", "3"))
    size = os.environ.get("SIZE", "256")
    models = [pathlib.Path(m) for m in os.environ.get("MODELS", "").split()] or default_models()
    common = ["--width", size, "--height", size, "--quiet"]
    with tempfile.TemporaryDirectory(prefix="nurbsrt-many-") as tmp:
        tmp = pathlib.Path(tmp)
        (tmp / "in").mkdir()
        files = distinct_copies(models, n, tmp / "in")
        per_process, one_process = [], []
        for r in range(rounds):
            out = tmp / f"out-{r}"
            out.mkdir()
            t = time.monotonic()
            for f in files:
                subprocess.run([exe, "render", str(f), "-o", str(out / (f.stem + ".png"))] + common, check=True)
            per_process.append((time.monotonic() - t) / n)
            out = tmp / f"dir-{r}"
            out.mkdir()
            t = time.monotonic()
            subprocess.run([exe, "render"] + [str(f) for f in files] + ["--out-dir", str(out)] + common, check=True)
            one_process.append((time.monotonic() - t) / n)
            assert len(list(out.glob("*.png"))) == n
        a, b = statistics.median(per_process), statistics.median(one_process)
        print(f"{n} files of {len(models)} small STEP models, {size}x{size}, {rounds} rounds, "
              f"load {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
        print("| way | per file (median of rounds) |\n|---|---|")
        print(f"| one process per file | {a * 1000:.0f} ms |")
        print(f"| one `--out-dir` process | {b * 1000:.0f} ms |")
        print(f"| ratio | {b / a:.2f} |")


if __name__ == "__main__":
    main()
