"""An identity: the certificate, private key and CA a process presents on Zenoh TLS links.

``Identity.load("alice")`` finds ``alice.crt``, ``alice.key`` and ``ca.crt`` in the key store
(``~/.config/dronewrapper/keys``, ``$DRONEWRAPPER_KEYS``, or ``keys_dir``); a path to a
``.crt`` file works too (its ``.key`` and the ``ca.crt`` beside it). ``tls_config`` is the
``transport/link/tls`` section of a Zenoh config for it (mutual TLS: each side shows its
certificate and checks the other's against the project CA).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from dronewrapper.security.keystore import KeyStore, check_name


@dataclass(frozen=True)
class Identity:
    """Paths of one identity's PEM files."""

    name: str
    cert: Path
    key: Path
    ca: Path

    @classmethod
    def load(cls, identity: str | Path, keys_dir: str | Path | None = None) -> Identity:
        """Resolve ``identity`` (a name in the key store, or a path to NAME.crt).

        Raises:
            FileNotFoundError: a file is missing (the message names it).
        """
        text = str(identity)
        if text.endswith(".crt") or "/" in text:
            cert = Path(text).expanduser()
            found = cls(cert.stem, cert, cert.with_suffix(".key"), cert.parent / "ca.crt")
        else:
            store = KeyStore(keys_dir)
            name = check_name(text)
            found = cls(name, store.cert(name), store.key(name), store.ca_cert)
        for path in (found.cert, found.key, found.ca):
            if not path.is_file():
                raise FileNotFoundError(
                    f"identity {text!r}: {path} is missing "
                    "(issue one with `dronewrapper keys issue NAME --role ROLE`)"
                )
        return found

    def tls_config(self) -> dict[str, Any]:
        """The Zenoh ``transport/link/tls`` settings for this identity (mTLS both ways)."""
        return {
            "root_ca_certificate": str(self.ca),
            "listen_private_key": str(self.key),
            "listen_certificate": str(self.cert),
            "enable_mtls": True,
            "connect_private_key": str(self.key),
            "connect_certificate": str(self.cert),
            "verify_name_on_connect": True,
            "close_link_on_expiration": True,
        }
