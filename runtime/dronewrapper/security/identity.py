"""An identity: the certificate, private key and CA a process presents on Zenoh TLS links.

``Identity.load("alice")`` finds ``alice.crt``, ``alice.key`` and ``ca.crt`` in the key store
(``~/.config/dronewrapper/keys``, ``$DRONEWRAPPER_KEYS``, or ``keys_dir``); a path to a
``.crt`` file works too (its ``.key`` and the ``ca.crt`` beside it). ``tls_config`` is the
``transport/link/tls`` section of a Zenoh config for it (mutual TLS: each side shows its
certificate and checks the other's against the project CA). ``subject()`` reads what the
certificate says about its holder: the common name (the router's access control binds roles
and commands to it) and the role, which ``dronewrapper keys issue`` writes as the subject's
organizational unit, so a laptop knows its role without the drone's ``index.json``.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from dronewrapper.security.keystore import KeyStore, check_name


@dataclass(frozen=True)
class Subject:
    """What a certificate says about its holder: ``name`` (common name) and ``role`` (the
    organizational unit; ``""`` in certificates issued before roles were written there)."""

    name: str
    role: str


def read_subject(cert: Path) -> Subject:
    """The subject of the PEM certificate ``cert``; without ``cryptography`` installed (the SDK
    without the ``security`` extra), the file's stem and no role."""
    try:
        from cryptography import x509
        from cryptography.x509.oid import NameOID
    except ImportError:
        return Subject(cert.stem, "")
    subject = x509.load_pem_x509_certificate(cert.read_bytes()).subject

    def first(oid: object) -> str:
        values = subject.get_attributes_for_oid(oid)  # type: ignore[arg-type]
        return str(values[0].value) if values else ""

    return Subject(first(NameOID.COMMON_NAME) or cert.stem, first(NameOID.ORGANIZATIONAL_UNIT_NAME))


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

    def subject(self) -> Subject:
        """The certificate's name and role (see :func:`read_subject`)."""
        return read_subject(self.cert)

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
