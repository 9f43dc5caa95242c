"""The project's key store: a certificate authority, the certificates it issued, MAVLink keys.

One folder (``~/.config/dronewrapper/keys``, or ``$DRONEWRAPPER_KEYS``, or ``--keys DIR``)
holds everything; no online service is involved:

    ca.key, ca.crt          the project CA (ECDSA P-256, 10 years); ca.key never leaves this folder
    NAME.key, NAME.crt      one identity per drone, operator, observer or relay router (P-256)
    index.json              who was issued what: name, role, serial, expiry, revoked
    mavlink.key             the 32-byte MAVLink 2 signing key, as 64 hex digits

Every file is written with mode 0600 (the folder 0700). A certificate's common name is the
identity's name and its organizational unit the role (what its holder's SDK reads to know its
role). The router's access control grants roles from ``index.json`` only, so a
revoked name loses every permission (Zenoh's TLS has no revocation list; the name is simply no
longer in any role, and the default is deny). A revoked name cannot be issued again.
"""

from __future__ import annotations

import datetime as dt
import ipaddress
import json
import os
import re
import secrets
from dataclasses import asdict, dataclass
from pathlib import Path

ROLES = ("drone", "operator", "observer", "relay")
ENV_KEYS = "DRONEWRAPPER_KEYS"
NAME_PATTERN = r"[A-Za-z0-9][A-Za-z0-9_\-.]{0,62}"
CA_DAYS = 3650
DEFAULT_DAYS = 365
MAVLINK_KEY_BYTES = 32


class KeyStoreError(Exception):
    """A key store operation cannot be done (the message says why)."""


def default_keys_dir() -> Path:
    """``$DRONEWRAPPER_KEYS`` or ``~/.config/dronewrapper/keys``."""
    env = os.environ.get(ENV_KEYS)
    if env:
        return Path(env).expanduser()
    base = os.environ.get("XDG_CONFIG_HOME") or Path.home() / ".config"
    return Path(base) / "dronewrapper" / "keys"


@dataclass
class Issued:
    """One issued certificate, as recorded in ``index.json``."""

    name: str
    role: str
    serial: str  # hex
    not_after: str  # ISO 8601, UTC
    revoked: bool = False

    def expired(self, now: dt.datetime) -> bool:
        return dt.datetime.fromisoformat(self.not_after) <= now


def _write_private(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` with mode 0600 from the start (never world-readable)."""
    tmp = path.with_suffix(path.suffix + ".tmp")
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
    try:
        os.write(fd, data)
    finally:
        os.close(fd)
    os.chmod(tmp, 0o600)
    os.replace(tmp, path)


def check_name(name: str) -> str:
    """A valid identity name (one Zenoh-safe chunk, used as the certificate's common name)."""
    if not isinstance(name, str) or not re.fullmatch(NAME_PATTERN, name) or name == "ca":
        raise KeyStoreError(f"identity name {name!r} must match {NAME_PATTERN} (and not be 'ca')")
    return name


class KeyStore:
    """The key store folder ``root`` (created on :meth:`init`)."""

    def __init__(self, root: Path | str | None = None) -> None:
        self.root = Path(root).expanduser() if root is not None else default_keys_dir()

    # ---- paths ----
    @property
    def ca_cert(self) -> Path:
        return self.root / "ca.crt"

    @property
    def ca_key(self) -> Path:
        return self.root / "ca.key"

    @property
    def index_path(self) -> Path:
        return self.root / "index.json"

    @property
    def mavlink_key(self) -> Path:
        return self.root / "mavlink.key"

    def cert(self, name: str) -> Path:
        return self.root / f"{check_name(name)}.crt"

    def key(self, name: str) -> Path:
        return self.root / f"{check_name(name)}.key"

    # ---- index ----
    def entries(self) -> list[Issued]:
        """Every certificate ever issued here (revoked ones included)."""
        if not self.index_path.exists():
            return []
        raw = json.loads(self.index_path.read_text())
        return [Issued(**item) for item in raw.get("issued", [])]

    def _save(self, entries: list[Issued]) -> None:
        body = json.dumps({"issued": [asdict(e) for e in entries]}, indent=2) + "\n"
        _write_private(self.index_path, body.encode())

    def names_by_role(self, now: dt.datetime | None = None) -> dict[str, list[str]]:
        """Role -> names of the valid (not revoked, not expired) certificates."""
        now = now or dt.datetime.now(dt.timezone.utc)
        out: dict[str, list[str]] = {role: [] for role in ROLES}
        for entry in self.entries():
            if not entry.revoked and not entry.expired(now):
                out[entry.role].append(entry.name)
        return out

    # ---- operations ----
    def init(self, *, ca_name: str = "dronewrapper-ca") -> Path:
        """Create the folder and the project CA (refuses to overwrite an existing CA)."""
        from cryptography import x509
        from cryptography.hazmat.primitives import hashes
        from cryptography.hazmat.primitives.asymmetric import ec
        from cryptography.x509.oid import NameOID

        if self.ca_key.exists():
            raise KeyStoreError(
                f"{self.ca_key} exists; the CA is made once (remove it to start over)"
            )
        self.root.mkdir(parents=True, exist_ok=True)
        os.chmod(self.root, 0o700)
        key = ec.generate_private_key(ec.SECP256R1())
        subject = x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, ca_name)])
        now = dt.datetime.now(dt.timezone.utc)
        cert = (
            x509.CertificateBuilder()
            .subject_name(subject)
            .issuer_name(subject)
            .public_key(key.public_key())
            .serial_number(x509.random_serial_number())
            .not_valid_before(now - dt.timedelta(minutes=5))
            .not_valid_after(now + dt.timedelta(days=CA_DAYS))
            .add_extension(x509.BasicConstraints(ca=True, path_length=0), critical=True)
            .add_extension(_key_usage(ca=True), critical=True)
            .add_extension(x509.SubjectKeyIdentifier.from_public_key(key.public_key()), False)
            .sign(key, hashes.SHA256())
        )
        _write_private(self.ca_key, _pem_key(key))
        _write_private(self.ca_cert, _pem_cert(cert))
        self._save([])
        return self.ca_cert

    def issue(
        self,
        name: str,
        role: str,
        *,
        days: float = DEFAULT_DAYS,
        hosts: list[str] | tuple[str, ...] = (),
        now: dt.datetime | None = None,
    ) -> Issued:
        """Issue ``name``'s certificate for ``role`` (``hosts``: extra DNS names or IPs it serves
        on, for a drone's router; ``localhost`` and 127.0.0.1 are always included)."""
        from cryptography import x509
        from cryptography.hazmat.primitives import hashes, serialization
        from cryptography.hazmat.primitives.asymmetric import ec
        from cryptography.x509.oid import ExtendedKeyUsageOID, NameOID

        check_name(name)
        if role not in ROLES:
            raise KeyStoreError(f"role must be one of {', '.join(ROLES)}, got {role!r}")
        if not days > 0:
            raise KeyStoreError(f"days must be > 0, got {days}")
        if not self.ca_key.exists():
            raise KeyStoreError(f"no CA in {self.root}: run `dronewrapper keys init` first")
        entries = self.entries()
        if any(e.name == name and e.revoked for e in entries):
            raise KeyStoreError(f"{name!r} was revoked; issue a certificate under a new name")
        ca_key = serialization.load_pem_private_key(self.ca_key.read_bytes(), None)
        if not isinstance(ca_key, ec.EllipticCurvePrivateKey):  # `keys init` makes one
            raise KeyStoreError(f"{self.ca_key} is not an elliptic-curve private key")
        ca_cert = x509.load_pem_x509_certificate(self.ca_cert.read_bytes())
        now = now or dt.datetime.now(dt.timezone.utc)
        key = ec.generate_private_key(ec.SECP256R1())
        sans: list[x509.GeneralName] = [x509.DNSName(name), x509.DNSName("localhost")]
        sans.append(x509.IPAddress(ipaddress.ip_address("127.0.0.1")))
        for host in hosts:
            try:
                sans.append(x509.IPAddress(ipaddress.ip_address(host)))
            except ValueError:
                sans.append(x509.DNSName(host))
        serial = x509.random_serial_number()
        not_after = now + dt.timedelta(days=days)
        cert = (
            x509.CertificateBuilder()
            .subject_name(
                x509.Name(
                    [
                        x509.NameAttribute(NameOID.COMMON_NAME, name),
                        x509.NameAttribute(NameOID.ORGANIZATIONAL_UNIT_NAME, role),
                    ]
                )
            )
            .issuer_name(ca_cert.subject)
            .public_key(key.public_key())
            .serial_number(serial)
            .not_valid_before(min(now, dt.datetime.now(dt.timezone.utc)) - dt.timedelta(minutes=5))
            .not_valid_after(not_after)
            .add_extension(x509.BasicConstraints(ca=False, path_length=None), critical=True)
            .add_extension(_key_usage(ca=False), critical=True)
            .add_extension(
                x509.ExtendedKeyUsage(
                    [ExtendedKeyUsageOID.SERVER_AUTH, ExtendedKeyUsageOID.CLIENT_AUTH]
                ),
                critical=False,
            )
            .add_extension(x509.SubjectAlternativeName(sans), critical=False)
            .sign(ca_key, hashes.SHA256())
        )
        _write_private(self.key(name), _pem_key(key))
        _write_private(self.cert(name), _pem_cert(cert))
        entry = Issued(name, role, f"{serial:x}", not_after.isoformat())
        self._save([e for e in entries if e.name != name] + [entry])
        return entry

    def revoke(self, name: str) -> Issued:
        """Mark ``name`` revoked (the router's next policy gives it no permission at all)."""
        entries = self.entries()
        for entry in entries:
            if entry.name == check_name(name):
                entry.revoked = True
                self._save(entries)
                return entry
        raise KeyStoreError(f"no certificate named {name!r} in {self.root}")

    def export(self, name: str, dest: Path | str, *, router: bool = False) -> list[Path]:
        """Copy what ``name`` needs elsewhere (``ca.crt``, ``NAME.crt``, ``NAME.key``; never
        ``ca.key``) into the folder ``dest``, each 0600: a key folder for that machine.

        ``router``: that machine runs a router with access control, which grants each
        certificate its role from ``index.json`` (names, roles, expiry; no secret): copy it too.
        """
        files = [self.ca_cert, self.cert(name), self.key(name)]
        if router:
            files.append(self.index_path)
        for path in files:
            if not path.is_file():
                raise KeyStoreError(f"{path} is missing: issue {name!r} first")
        if any(e.name == name and e.revoked for e in self.entries()):
            raise KeyStoreError(f"{name!r} was revoked")
        folder = Path(dest).expanduser()
        folder.mkdir(parents=True, exist_ok=True)
        os.chmod(folder, 0o700)
        out = []
        for path in files:
            _write_private(folder / path.name, path.read_bytes())
            out.append(folder / path.name)
        return out

    def new_mavlink_key(self, *, force: bool = False) -> bytes:
        """Make the 32-byte MAVLink 2 signing key (``mavlink.key``, 64 hex digits, 0600)."""
        if self.mavlink_key.exists() and not force:
            raise KeyStoreError(f"{self.mavlink_key} exists (--force replaces it)")
        self.root.mkdir(parents=True, exist_ok=True)
        key = secrets.token_bytes(MAVLINK_KEY_BYTES)
        _write_private(self.mavlink_key, key.hex().encode() + b"\n")
        return key


def read_mavlink_key(path: Path | str) -> bytes:
    """The 32-byte MAVLink signing key in ``path`` (64 hex digits, or 32 raw bytes)."""
    data = Path(path).expanduser().read_bytes()
    text = data.strip()
    if len(text) == 2 * MAVLINK_KEY_BYTES:
        try:
            return bytes.fromhex(text.decode("ascii"))
        except (UnicodeDecodeError, ValueError):
            pass
    if len(data) == MAVLINK_KEY_BYTES:
        return data
    raise KeyStoreError(f"{path}: a MAVLink key is 64 hex digits or 32 bytes, got {len(data)}")


def _pem_key(key: object) -> bytes:
    from cryptography.hazmat.primitives import serialization

    return key.private_bytes(  # type: ignore[attr-defined]
        serialization.Encoding.PEM,
        serialization.PrivateFormat.PKCS8,
        serialization.NoEncryption(),
    )


def _pem_cert(cert: object) -> bytes:
    from cryptography.hazmat.primitives import serialization

    return cert.public_bytes(serialization.Encoding.PEM)  # type: ignore[attr-defined]


def _key_usage(*, ca: bool):
    from cryptography import x509

    return x509.KeyUsage(
        digital_signature=not ca,
        content_commitment=False,
        key_encipherment=False,
        data_encipherment=False,
        key_agreement=not ca,
        key_cert_sign=ca,
        crl_sign=ca,
        encipher_only=False,
        decipher_only=False,
    )
