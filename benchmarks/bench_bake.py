"""Keys baked in chunks: the longest single chunk (what one play tick or one export turn holds the GUI thread)
against the one-go bake of the same keys it replaces.

    python benchmarks/bench_bake.py [--frames N]

Keys at frame 0 (standing) and frame N - 1 (the left hand reached 0.4 m out), biped, 12 solver steps per
in-between frame. Prints the one-go bake's time, the time per frame, the longest chunk of the timeline's play
tick (``BAKE_FRAMES_PER_TICK``) and of Export's event-loop turn (``CHUNK_FRAMES``), and the ratios. One run; the
load of the machine is stated by whoever runs it.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from gsik_studio.model import Document
from gsik_studio.model.bake import KeyedBake
from gsik_studio.model.timeline import BAKE_FRAMES_PER_TICK
from gsik_studio.progress import CHUNK_FRAMES


def keyed_document(n_frames: int) -> Document:
    doc = Document()
    doc.timeline.add_key(0)
    doc.move_target("left_hand", np.array(doc.targets["left_hand"].position) + [0.0, 0.25, 0.3])
    for _ in range(200):
        doc.step()
    doc.timeline.add_key(n_frames - 1)
    return doc


def longest_chunk(doc: Document, chunk: int) -> tuple[float, float]:
    """(longest chunk [s], whole bake [s]) baking every frame ``chunk`` at a time."""
    tl = doc.timeline
    bake = KeyedBake(doc.skeleton, doc.settings, tl.keys, tl.frame_time, n_frames=tl.n_frames)
    longest, start = 0.0, time.perf_counter()
    while not bake.done:
        t = time.perf_counter()
        bake.step(chunk)
        longest = max(longest, time.perf_counter() - t)
    return longest, time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=2000, help="frames of the key sequence (default 2000)")
    n = parser.parse_args().frames
    doc = keyed_document(n)
    longest_chunk(doc, n)  # warm-up: the kernels compiled, caches filled
    one_go, _ = longest_chunk(doc, n)
    print(f"keys at 0 and {n - 1}: one-go bake {one_go:.2f} s ({one_go / n * 1e3:.3f} ms per frame)")
    for name, chunk in (("play tick", BAKE_FRAMES_PER_TICK), ("export turn", CHUNK_FRAMES)):
        longest, total = longest_chunk(doc, chunk)
        print(f"{name:12s} {chunk:3d} frames: longest chunk {longest * 1e3:6.1f} ms = {longest / one_go:.4f} of "
              f"the one-go bake; all chunks {total:.2f} s ({total / one_go:.2f} x one go)")


if __name__ == "__main__":
    main()
