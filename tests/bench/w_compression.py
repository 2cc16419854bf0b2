"""How far the contact compliance W of a shipped scene compresses as a hierarchical matrix.

``python tests/bench/w_compression.py SCENE [--size H] [--eps 1e-4,1e-6,1e-8] [--eta 1,2]``
builds ``examples/SCENE.toml`` (with ``contact_size = H`` mm on every body that has one),
forms its dense W and prints, for each admissibility η and tolerance ε, the storage of a
hierarchical W against the dense one, as JSON lines.

The cluster tree bisects the contact points along their widest extent down to at most
``--leaf`` points; a block of two clusters is low-rank (admissible) when the larger diameter
is at most η times their distance, and its rank is the number of singular values above ε
times its largest. Inadmissible leaf blocks stay dense. A measurement for issue 14 (does a
compressed W pay at 2.5 mm on the counterweight?), not a solver: W is formed dense first.
Units: mm, mm/N.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests" / "bench"))

import scene_run  # noqa: E402
from contact.structure import ContactSpace  # noqa: E402
from pipelines import scene as scenes  # noqa: E402
from pipelines.build import build  # noqa: E402
from pipelines.coupling import multibody_loading  # noqa: E402
from reduction.threads import pin_process  # noqa: E402


def cluster_tree(points: np.ndarray, leaf: int) -> tuple:
    """(indices, children or None), bisecting along the widest extent."""
    def split(index):
        if index.size <= leaf:
            return index, None
        spread = points[index].max(axis=0) - points[index].min(axis=0)
        order = index[np.argsort(points[index, np.argmax(spread)], kind="stable")]
        half = order.size // 2
        return index, (split(order[:half]), split(order[half:]))
    return split(np.arange(len(points)))


def blocks(points: np.ndarray, tree: tuple, eta: float) -> list[tuple[bool, np.ndarray, np.ndarray]]:
    """The block partition: (admissible, rows' points, columns' points)."""
    def box(index):
        return points[index].min(axis=0), points[index].max(axis=0)

    def diameter(index):
        low, high = box(index)
        return float(np.linalg.norm(high - low))

    def distance(a, b):
        (la, ha), (lb, hb) = box(a), box(b)
        return float(np.linalg.norm(np.maximum(0.0, np.maximum(la - hb, lb - ha))))

    out = []

    def visit(a, b):
        if max(diameter(a[0]), diameter(b[0])) <= eta * distance(a[0], b[0]):
            out.append((True, a[0], b[0]))
        elif a[1] is None and b[1] is None:
            out.append((False, a[0], b[0]))
        else:
            for x in (a[1] if a[1] is not None else (a,)):
                for y in (b[1] if b[1] is not None else (b,)):
                    visit(x, y)
    visit(tree, tree)
    return out


def storage(W: np.ndarray, dim: int, partition: list, eps_list: list[float]) -> dict:
    """Fraction of W's dense storage a hierarchical W needs at each ε (and its dense part)."""
    def rows(index):
        return (index[:, None] * dim + np.arange(dim)).ravel()
    dense = sum(a.size * b.size for admissible, a, b in partition if not admissible) * dim * dim
    spectra = [(np.linalg.svd(W[np.ix_(rows(a), rows(b))], compute_uv=False), a.size * dim + b.size * dim)
               for admissible, a, b in partition if admissible]
    result = {}
    for eps in eps_list:
        low_rank = sum(int(np.sum(s > eps * s[0])) * width for s, width in spectra)
        result[f"{eps:g}"] = (dense + low_rank) / W.size
    return {"dense_part": dense / W.size, "storage": result}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scene", help="name of a scene in examples/")
    parser.add_argument("--size", type=float, default=None, help="contact mesh size, mm")
    parser.add_argument("--eps", default="1e-4,1e-6,1e-8", help="relative singular value cut-offs")
    parser.add_argument("--eta", default="1,2", help="admissibility parameters")
    parser.add_argument("--leaf", type=int, default=32, help="points per leaf cluster")
    args = parser.parse_args(argv)
    pin_process()
    path = ROOT / "examples" / f"{args.scene}.toml"
    scene = scenes.load(path, scene_run.overrides(path, args.size, None))
    multibody = multibody_loading(scene, None) if "coupling" in scene.data else None
    model = build(scene, multibody=multibody)
    W = ContactSpace(model.assembly.structure).W
    points = model.assembly.pairing.slave.coordinates
    dim = model.assembly.structure.dim
    tree = cluster_tree(points, args.leaf)
    for eta in (float(e) for e in args.eta.split(",")):
        partition = blocks(points, tree, eta)
        figures = storage(W, dim, partition, [float(e) for e in args.eps.split(",")])
        print(json.dumps({"scene": args.scene, "size": args.size, "rows": W.shape[0], "eta": eta,
                          "blocks": len(partition), "low_rank_blocks": sum(p[0] for p in partition),
                          **figures}), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
