"""CPU time of ``switchobs transform``'s search mode: from f, g, h to s(y), phi and the normal form.

Systems (``examples/systems/``): the wheel with Burckhardt's tyre of seed 000 (n = 3, exponential, five
symbolic parameters, external v_x), the wheel of seed 001 (n = 2) and the polynomial examples poly2, poly3,
poly4 (the observer form with s(y) = 1 + y^2 moved by x_i = z_i + q z_(i-1)^2, symbolic k and q).  Each run is
cold: sympy's cache and the kappa_n cache are cleared before it.  In-process CPU seconds
(``time.process_time``), median [min–max].  Run: ``python benchmarks/transform.py [--quick]`` (``--quick``: one
run each, results not written).
"""

from __future__ import annotations

import argparse
from pathlib import Path

from _harness import MIN_REPEATS, cpu, publish

SYSTEMS = Path(__file__).resolve().parents[1] / "examples" / "systems"
CASES = (("wheel-burckhardt", "seed 000 eq. (4)-(6), c3 a state"), ("xbs-aguado", "seed 001 eq. (2.4)-(2.5)"),
         ("poly2", "polynomial"), ("poly3", "polynomial"), ("poly4", "polynomial"))


def _clear_caches() -> None:
    from sympy.core.cache import clear_cache

    from switchobs.transform._lie import kappa

    clear_cache()
    kappa.cache_clear()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="one run per system, results not written")
    args = parser.parse_args()
    from switchobs.transform import System, search_transformation

    repeats = 1 if args.quick else MIN_REPEATS
    rows = ["| system | n | parameters | what | s(y) | search s |", "| --- | ---: | ---: | --- | --- | ---: |"]
    for name, what in CASES:
        system = System.from_toml(SYSTEMS / f"{name}.toml")
        results = []
        stats = cpu(lambda: results.append(search_transformation(system)), repeats, setup=_clear_caches)
        if not results[-1].exists:
            raise SystemExit(f"{name}: no transformation found ({results[-1].failing})")
        rows.append(f"| {name} | {system.n} | {len(system.parameters)} | {what} | `{results[-1].time_scale}` | "
                    f"{stats.show()} |")
    publish("transform", "Search mode (`search_transformation`, Lie derivatives to the substitution check) on "
            f"each system, cold, {repeats} run(s); CPU time in seconds (`time.process_time`), median [min–max].",
            [rows], ["Every run ends with the exact substitution check of the normal form it returns."],
            write=not args.quick)


if __name__ == "__main__":
    main()
