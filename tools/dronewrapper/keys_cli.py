"""``dronewrapper keys``: the project CA, certificates and the MAVLink signing key.

    dronewrapper keys init                                  make the project CA
    dronewrapper keys issue drone1 --role drone [--host IP] the drone's certificate (its router)
    dronewrapper keys issue alice --role operator           an operator (may fly)
    dronewrapper keys issue bob --role observer             an observer (may only watch)
    dronewrapper keys issue relay1 --role relay --host IP   a router between field and ground
    dronewrapper keys list                                  what was issued, valid or not
    dronewrapper keys revoke bob                            bob loses every permission
    dronewrapper keys export alice /media/usb/keys          alice's files for her laptop
    dronewrapper keys export relay1 DIR --router            its files and the roles (a router)
    dronewrapper keys mavlink                               the 32-byte MAVLink 2 signing key

Files live in ``--keys DIR`` (default ``$DRONEWRAPPER_KEYS`` or ``~/.config/dronewrapper/keys``),
each with mode 0600. A laptop needs ``ca.crt``, ``NAME.crt`` and ``NAME.key`` in its own key
folder (``export`` copies exactly those; ``--router`` adds ``index.json``, the roles a router's
access control grants); ``ca.key`` stays where the CA was made. Restart the router after
``issue`` or ``revoke`` (and export ``index.json`` again to other routers): its access control
is generated when it starts.
"""

from __future__ import annotations

import argparse
import datetime as dt
import sys
from collections.abc import Sequence

from dronewrapper.runtime.arguments import CommandParser
from dronewrapper.security.keystore import ROLES, KeyStore, KeyStoreError


def _parser() -> argparse.ArgumentParser:
    parser = CommandParser(
        prog="dronewrapper keys", description="project CA, certificates, MAVLink signing key"
    )
    parser.add_argument("--keys", default=None, metavar="DIR", help="key store folder")
    sub = parser.add_subparsers(dest="command", required=True)
    sub.add_parser("init", help="make the project CA")
    issue = sub.add_parser("issue", help="issue a certificate")
    issue.add_argument("name", help="identity name (the certificate's common name)")
    issue.add_argument("--role", required=True, choices=ROLES)
    issue.add_argument("--days", type=float, default=365.0, help="validity (default 365)")
    issue.add_argument(
        "--host", action="append", default=[], help="a DNS name or IP the drone serves on"
    )
    sub.add_parser("list", help="list issued certificates")
    revoke = sub.add_parser("revoke", help="revoke a certificate")
    revoke.add_argument("name")
    export = sub.add_parser("export", help="copy an identity's files for another machine")
    export.add_argument("name")
    export.add_argument("dest", help="folder to write ca.crt, NAME.crt, NAME.key into")
    export.add_argument(
        "--router", action="store_true", help="also index.json: that machine runs a router"
    )
    mav = sub.add_parser("mavlink", help="make the 32-byte MAVLink 2 signing key")
    mav.add_argument("--force", action="store_true", help="replace an existing key")
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run ``dronewrapper keys ...``; 0 on success, 1 with a message on stderr otherwise."""
    args = _parser().parse_args(argv)
    store = KeyStore(args.keys)
    try:
        if args.command == "init":
            print(f"project CA: {store.init()} (keep {store.ca_key} private)")
        elif args.command == "issue":
            entry = store.issue(args.name, args.role, days=args.days, hosts=args.host)
            print(f"{entry.role} {entry.name}: {store.cert(entry.name)}, {store.key(entry.name)}")
            print(f"valid until {entry.not_after}; restart the router to apply")
        elif args.command == "list":
            now = dt.datetime.now(dt.timezone.utc)
            for e in store.entries():
                status = "revoked" if e.revoked else "expired" if e.expired(now) else "valid"
                print(f"{e.name:20} {e.role:9} {status:8} until {e.not_after}  serial {e.serial}")
        elif args.command == "revoke":
            entry = store.revoke(args.name)
            print(f"revoked {entry.name} ({entry.role}); restart the router to apply")
        elif args.command == "export":
            paths = store.export(args.name, args.dest, router=args.router)
            print("wrote " + ", ".join(str(p) for p in paths))
            print(
                "on that machine, put them in ~/.config/dronewrapper/keys (or $DRONEWRAPPER_KEYS)"
            )
        elif args.command == "mavlink":
            store.new_mavlink_key(force=args.force)
            print(f"MAVLink signing key: {store.mavlink_key} (64 hex digits, mode 0600)")
    except (KeyStoreError, OSError) as exc:
        print(f"dronewrapper keys: {exc}", file=sys.stderr)
        return 1
    return 0
