"""``dronewrapper record | replay | foxglove``: the command lines of the record extra.

dronewrapper record [KEYEXPR...] -o FILE.mcap [--duration S] [--compressed-images]
dronewrapper record --info FILE.mcap
dronewrapper replay FILE.mcap [--rate R] [--loop] [--start S] [--keys KEYEXPR...] [--clock]
dronewrapper foxglove [KEYEXPR...] [--port 8765] [--raw-images]
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path

from dronewrapper.command_line import client_session, stop_on_signals
from dronewrapper.runtime.arguments import CommandParser
from dronewrapper.runtime.options import add_zenoh_args
from dronewrapper.runtime.service import setup_logging


def _quality(value: str) -> int:
    q = int(value)
    if not 1 <= q <= 100:
        raise argparse.ArgumentTypeError(f"JPEG quality must be 1..100, got {q}")
    return q


def _non_negative(value: str) -> float:
    x = float(value)
    if not x >= 0 or x == float("inf"):
        raise argparse.ArgumentTypeError(f"must be a finite number >= 0, got {value}")
    return x


def _positive(value: str) -> float:
    x = _non_negative(value)
    if x == 0:
        raise argparse.ArgumentTypeError(f"must be > 0, got {value}")
    return x


def record_main(argv: Sequence[str]) -> int:
    """``dronewrapper record``: the bus to MCAP, or ``--info FILE`` to summarise one."""
    parser = CommandParser(prog="dronewrapper record", description="the bus to MCAP")
    parser.add_argument("keyexprs", nargs="*", default=["**"], help="what to record (default **)")
    parser.add_argument("-o", "--output", metavar="FILE.mcap", help="the recording to write")
    parser.add_argument("--info", metavar="FILE.mcap", help="summarise a recording and exit")
    parser.add_argument(
        "--ros2",
        metavar="FILE.mcap",
        help="convert a recording to a ROS 2 bag (ros2msg + CDR) written to -o, and exit",
    )
    parser.add_argument("--duration", type=_non_negative, default=0.0, help="stop after S s")
    parser.add_argument(
        "--compressed-images", action="store_true", help="store raw camera frames as JPEG"
    )
    parser.add_argument("--jpeg-quality", type=_quality, default=80, help="default 80")
    parser.add_argument(
        "--image-rate", type=_non_negative, default=0.0, help="keep at most HZ frames/s per camera"
    )
    parser.add_argument("--compression", choices=("zstd", "lz4", "none"), default="zstd")
    add_zenoh_args(parser, default_mode="client")
    args = parser.parse_args(argv)
    from dronewrapper.record.reader import summarize

    if args.info:
        try:
            print(summarize(args.info).text())
        except OSError as exc:
            print(f"dronewrapper record: {exc}", file=sys.stderr)
            return 1
        return 0
    if not args.output:
        parser.error("-o FILE.mcap is required (or --info FILE)")
    if args.ros2:
        from dronewrapper.record.ros2_bag import convert_to_ros2

        try:
            written, skipped = convert_to_ros2(args.ros2, args.output, compression=args.compression)
        except OSError as exc:
            print(f"dronewrapper record: {exc}", file=sys.stderr)
            return 1
        left = ", ".join(sorted(skipped)) or "none"
        print(
            f"wrote {sum(written.values())} messages on {len(written)} ROS 2 topics to "
            f"{args.output} (left out, no ROS 2 type: {left})"
        )
        return 0
    from dronewrapper.echo import path_warning

    for keyexpr in args.keyexprs:
        if warning := path_warning(keyexpr):
            print(f"dronewrapper record: warning: {warning}", file=sys.stderr)
    from dronewrapper.record.capture import capture
    from dronewrapper.record.recorder import Recorder

    setup_logging()
    stop = stop_on_signals()
    session = client_session(args, "dronewrapper record")
    if session is None:
        return 1
    quality = args.jpeg_quality if args.compressed_images else None
    try:
        with (
            Path(args.output).open("wb") as f,
            Recorder(f, jpeg_quality=quality, compression=args.compression) as recorder,
        ):
            stats = capture(
                session,
                args.keyexprs,
                recorder,
                stop,
                duration=args.duration,
                image_rate_hz=args.image_rate,
            )
    finally:
        session.close()
    dropped = ", ".join(f"{k}={v}" for k, v in sorted(stats.dropped.items())) or "0"
    print(
        f"recorded {stats.written} messages on {len(recorder.counts)} keys to {args.output} "
        f"(dropped: {dropped})"
    )
    return 0


def replay_main(argv: Sequence[str]) -> int:
    """``dronewrapper replay``: a recording back on the bus with its original timing."""
    parser = CommandParser(prog="dronewrapper replay", description="MCAP to the bus")
    parser.add_argument("file", help="the recording (.mcap)")
    parser.add_argument("--rate", type=_positive, default=1.0, help="speed factor (default 1)")
    parser.add_argument("--loop", action="store_true", help="start again at the end")
    parser.add_argument("--start", type=_non_negative, default=0.0, help="skip the first S s")
    parser.add_argument("--keys", nargs="+", metavar="KEYEXPR", help="replay only these")
    parser.add_argument("--clock", action="store_true", help="publish the recorded time on clock")
    add_zenoh_args(parser, default_mode="client")
    args = parser.parse_args(argv)
    if not Path(args.file).is_file():
        print(f"dronewrapper replay: no such file: {args.file}", file=sys.stderr)
        return 1
    from dronewrapper.record.replayer import replay

    setup_logging()
    stop = stop_on_signals()
    session = client_session(args, "dronewrapper replay")
    if session is None:
        return 1
    try:
        stats = replay(
            session,
            args.file,
            stop,
            rate=args.rate,
            loop=args.loop,
            start_s=args.start,
            keys=args.keys,
            clock=args.clock,
        )
    finally:
        session.close()
    late = sorted(stats.lateness)
    p99 = late[int(0.99 * (len(late) - 1))] * 1e3 if late else 0.0
    print(f"replayed {stats.published} messages, {stats.loops} pass(es), p99 late {p99:.1f} ms")
    return 0


def foxglove_main(argv: Sequence[str]) -> int:
    """``dronewrapper foxglove``: the live bus on a Foxglove WebSocket (ws://HOST:PORT)."""
    from dronewrapper.record.live import DEFAULT_PORT

    parser = CommandParser(prog="dronewrapper foxglove", description="live Foxglove")
    parser.add_argument("keyexprs", nargs="*", default=["**"], help="what to serve (default **)")
    parser.add_argument("--host", default="127.0.0.1", help="listen address (default loopback)")
    parser.add_argument("--port", type=int, default=DEFAULT_PORT, help=f"default {DEFAULT_PORT}")
    parser.add_argument("--raw-images", action="store_true", help="send camera frames raw")
    parser.add_argument("--jpeg-quality", type=_quality, default=80, help="default 80")
    parser.add_argument("--duration", type=_non_negative, default=0.0, help="stop after S s")
    add_zenoh_args(parser, default_mode="client")
    args = parser.parse_args(argv)
    if not 0 <= args.port <= 65535:
        parser.error(f"--port must be 0..65535, got {args.port}")
    from dronewrapper.record.live import FoxgloveBridge, serve

    setup_logging()
    stop = stop_on_signals()
    session = client_session(args, "dronewrapper foxglove")
    if session is None:
        return 1
    quality = None if args.raw_images else args.jpeg_quality
    try:
        with FoxgloveBridge(host=args.host, port=args.port, jpeg_quality=quality) as bridge:
            print(f"Foxglove: open ws://{args.host}:{bridge.port}", flush=True)
            serve(session, args.keyexprs, bridge, stop, duration=args.duration)
    except (OSError, RuntimeError) as exc:
        print(f"dronewrapper foxglove: {exc}", file=sys.stderr)
        return 1
    finally:
        session.close()
    return 0
