"""``switchobs replay``: a measurement log (MDF4, Parquet, CSV) through the encoder chain and an XBS observer."""

from __future__ import annotations

import argparse
import contextlib
import sys

from .._atomic import check_output_file
from .._progress import progress
from ..exceptions import LogError
from ..loop import OBSERVER_KINDS
from ..spec import METHODS
from ._common import emit_json

__all__ = ["register"]


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "replay",
        description="Replay a measurement log through the wheel-encoder chain (TSA, three-stage compensation, "
                    "notch) and an XBS observer: the channel map (TOML) names the log's encoder edges, tooth "
                    "counter or wheel speed, vehicle speed or accelerometer and brake pressure or its rate, "
                    "with their units. The estimates, the observer's status codes and the chain's signals go to "
                    "--out (MDF4, Parquet or CSV). Exit 1 when the observer refuses a step. See docs/replay.md.")
    p.add_argument("log", metavar="LOG", help="the log: .mf4 (asammdf), .parquet (pyarrow) or .csv")
    p.add_argument("--channels", required=True, metavar="MAP.toml", help="the channel map ('-': standard input)")
    p.add_argument("--observer", choices=OBSERVER_KINDS, default="xbs4",
                   help="XBS observer (default xbs4; none: the chain only)")
    p.add_argument("--method", choices=METHODS, default="radau3",
                   help="observer step method (default radau3, certified for every step length)")
    p.add_argument("--beta", type=float, help="observer rate beta in the rescaled time (default the factory's)")
    p.add_argument("--observer-impl", choices=("python", "c"), default="python",
                   help="the Python reference observer or the generated C (compiled with the system compiler)")
    p.add_argument("--out", metavar="RESULT", help="write the signals here (.mf4, .parquet or .csv; another "
                                                    "ending: the log's format)")
    p.add_argument("--format", choices=("mdf", "parquet", "csv"), help="format of --out (default by its ending)")
    p.add_argument("--plot", metavar="PNG", help="write the figure (wheel speed, x2, XBS estimate) to this file")
    p.add_argument("--json", action="store_true", help="print the summary as JSON")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from ..logs import ChannelMap, LogStream, log_format, plot_replay, read_log, result_writer
    from ..loop import ReplayResult, stream_replay

    fmt = None
    if args.out is not None:
        if args.out == "-":
            raise LogError("--out -: a log is a binary file; give a file name")
        fmt = args.format or log_format(args.out, default=log_format(args.log))
        check_output_file(args.out, what="the result")
    elif args.format is not None:
        raise LogError("--format only applies with --out")
    if args.plot:
        check_output_file(args.plot, what="the plot")
    cmap = ChannelMap.from_toml(args.channels)
    progress(f"replay: reading {args.log}")
    # the log read, replayed and written piece by piece (memory bounded whatever its length)
    signals = LogStream(read_log(args.log, time_channel=cmap.time.channel, time_factor=cmap.time.factor), cmap)
    pieces: list[dict] = []
    with contextlib.ExitStack() as stack:
        # each piece of the replay goes to the result as it comes (only the figure needs them all)
        sinks = [stack.enter_context(result_writer(args.out, fmt=fmt)).append] if args.out is not None else []
        if args.plot:
            sinks.append(pieces.append)
        if args.out is not None:
            progress(f"replay: writing {args.out}")

        def write(piece: dict) -> None:
            for sink in sinks:
                sink(piece)
        summary = stream_replay(signals, write, observer=args.observer,
                                method=args.method, beta=args.beta, impl=args.observer_impl, vehicle=cmap.vehicle,
                                **cmap.chain_options())
    if args.plot:
        from .._figures import save_figure
        save_figure(plot_replay(ReplayResult.join(pieces, summary)), args.plot)
    if args.json:
        emit_json(summary.to_json())
    else:
        print(summary)
        for path, what in ((args.out, "signals"), (args.plot, "plot")):
            if path:
                print(f"{what} written to {path}")
    if summary.outcome != "ok":
        print(f"switchobs replay: failed: {summary.message}", file=sys.stderr)
        return 1
    return 0
