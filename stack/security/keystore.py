"""A keystore for the bus: a certificate authority and the identities it issues (``stack keys``).

As ROS 2's ``ros2 security create_keystore`` / ``create_enclave`` give each node an identity its DDS Security checks,
a keystore gives each member of a stack spread over machines an X.509 identity its Zenoh links check (mutual TLS):

- ``DIR/ca.pem``, ``DIR/ca.key``: the authority, an EC P-256 key and a self-signed certificate
  (``basicConstraints=CA:TRUE``), which signs every identity and is the root each side verifies the other against;
- ``DIR/identities/NAME.pem``, ``NAME.key``: an identity, its certificate naming it (``CN=NAME``) and its role
  (``OU=ROLE``: ``host``, the modules and links a host of the profile runs; ``operator``, who may command;
  ``observer``, who may only read), valid for TLS server and client alike (Zenoh's listener checks a client's
  certificate, a client the listener's name), with the names and addresses it is reached at as subject alternative
  names (a TLS client refuses a certificate that does not name the host it dialled).

Private keys are written with owner-only permissions (0600) in directories only the owner may enter (0700), and
never overwritten: a name is issued once.
"""

from __future__ import annotations

import datetime
import ipaddress
import os
from dataclasses import dataclass
from pathlib import Path

from cryptography import x509
from cryptography.hazmat.primitives import hashes, serialization
from cryptography.hazmat.primitives.asymmetric import ec
from cryptography.x509.oid import ExtendedKeyUsageOID, NameOID

from stack.bus import keys
from stack.security.roles import ROLES

CA_CERT, CA_KEY = "ca.pem", "ca.key"  # stack.supervisor.profile looks for ca.pem without importing this
IDENTITIES = "identities"
CA_DAYS = 3650
IDENTITY_DAYS = 365
LOOPBACK_NAMES = ("localhost", "127.0.0.1")


class KeystoreError(ValueError):
    """A keystore operation that cannot be done, with why."""


@dataclass(frozen=True)
class Identity:
    name: str
    role: str
    not_after: datetime.datetime
    names: tuple[str, ...]
    """The DNS names and addresses it is valid for."""
    cert: Path
    key: Path

    def expired(self, now: datetime.datetime | None = None) -> bool:
        return (now or datetime.datetime.now(datetime.UTC)) > self.not_after


def _now() -> datetime.datetime:
    return datetime.datetime.now(datetime.UTC)


def _write_key(path: Path, key: ec.EllipticCurvePrivateKey) -> None:
    pem = key.private_bytes(serialization.Encoding.PEM, serialization.PrivateFormat.PKCS8, serialization.NoEncryption())
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    with os.fdopen(fd, "wb") as f:
        f.write(pem)


def _write_cert(path: Path, cert: x509.Certificate) -> None:
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o644)
    with os.fdopen(fd, "wb") as f:
        f.write(cert.public_bytes(serialization.Encoding.PEM))


def _private_dir(path: Path) -> None:
    path.mkdir(mode=0o700, parents=True, exist_ok=True)
    os.chmod(path, 0o700)


def init_keystore(root: Path, organisation: str = "stack") -> Path:
    """A new authority in ``root`` (created, or empty); the path of its certificate."""
    if (root / CA_KEY).exists() or (root / CA_CERT).exists():
        raise KeystoreError(f"{root}: a keystore is already there ({CA_CERT}); issue identities from it")
    _private_dir(root)
    _private_dir(root / IDENTITIES)
    key = ec.generate_private_key(ec.SECP256R1())
    subject = x509.Name(
        [
            x509.NameAttribute(NameOID.ORGANIZATION_NAME, organisation),
            x509.NameAttribute(NameOID.COMMON_NAME, "stack CA"),
        ]
    )
    now = _now()
    cert = (
        x509.CertificateBuilder()
        .subject_name(subject)
        .issuer_name(subject)
        .public_key(key.public_key())
        .serial_number(x509.random_serial_number())
        .not_valid_before(now - datetime.timedelta(minutes=5))
        .not_valid_after(now + datetime.timedelta(days=CA_DAYS))
        .add_extension(x509.BasicConstraints(ca=True, path_length=0), critical=True)
        .add_extension(
            x509.KeyUsage(False, False, False, False, False, True, True, False, False), critical=True
        )
        .add_extension(x509.SubjectKeyIdentifier.from_public_key(key.public_key()), critical=False)
        .sign(key, hashes.SHA256())
    )
    _write_key(root / CA_KEY, key)
    _write_cert(root / CA_CERT, cert)
    return root / CA_CERT


def _authority(root: Path) -> tuple[x509.Certificate, ec.EllipticCurvePrivateKey]:
    if not (root / CA_CERT).exists() or not (root / CA_KEY).exists():
        raise KeystoreError(f"{root}: no keystore there (make one with `stack keys init {root}`)")
    cert = x509.load_pem_x509_certificate((root / CA_CERT).read_bytes())
    key = serialization.load_pem_private_key((root / CA_KEY).read_bytes(), password=None)
    if not isinstance(key, ec.EllipticCurvePrivateKey):
        raise KeystoreError(f"{root / CA_KEY}: not the EC key of a stack keystore")
    return cert, key


def _alternative_name(name: str) -> x509.GeneralName:
    try:
        return x509.IPAddress(ipaddress.ip_address(name))
    except ValueError:
        return x509.DNSName(name)


def issue_identity(
    root: Path, name: str, role: str, addresses: tuple[str, ...] = (), days: int = IDENTITY_DAYS
) -> Identity:
    """Identity ``name`` with ``role``, valid for ``days`` at its name, ``addresses`` (host names or IP addresses
    it is reached at) and loopback."""
    keys.check_name("identity", name)
    if role not in ROLES:
        raise KeystoreError(f"role {role!r} is not one of {', '.join(ROLES)}")
    if days < 1:
        raise KeystoreError(f"an identity is valid for at least a day, not {days}")
    ca_cert, ca_key = _authority(root)
    cert_path, key_path = root / IDENTITIES / f"{name}.pem", root / IDENTITIES / f"{name}.key"
    if cert_path.exists() or key_path.exists():
        raise KeystoreError(f"{root}: identity {name} was issued already ({cert_path})")
    names = tuple(dict.fromkeys((name, *addresses, *LOOPBACK_NAMES)))
    key = ec.generate_private_key(ec.SECP256R1())
    now = _now()
    subject = x509.Name(
        [x509.NameAttribute(NameOID.ORGANIZATIONAL_UNIT_NAME, role), x509.NameAttribute(NameOID.COMMON_NAME, name)]
    )
    ca_ski = ca_cert.extensions.get_extension_for_class(x509.SubjectKeyIdentifier).value
    cert = (
        x509.CertificateBuilder()
        .subject_name(subject)
        .issuer_name(ca_cert.subject)
        .public_key(key.public_key())
        .serial_number(x509.random_serial_number())
        .not_valid_before(now - datetime.timedelta(minutes=5))
        .not_valid_after(now + datetime.timedelta(days=days))
        .add_extension(x509.BasicConstraints(ca=False, path_length=None), critical=True)
        .add_extension(x509.KeyUsage(True, False, False, False, False, False, False, False, False), critical=True)
        .add_extension(
            x509.ExtendedKeyUsage([ExtendedKeyUsageOID.SERVER_AUTH, ExtendedKeyUsageOID.CLIENT_AUTH]), critical=False
        )
        .add_extension(x509.SubjectAlternativeName([_alternative_name(n) for n in names]), critical=False)
        .add_extension(x509.AuthorityKeyIdentifier.from_issuer_subject_key_identifier(ca_ski), critical=False)
        .sign(ca_key, hashes.SHA256())
    )
    _write_key(key_path, key)
    _write_cert(cert_path, cert)
    return read_identity(root, name)


def read_identity(root: Path, name: str) -> Identity:
    cert_path = root / IDENTITIES / f"{name}.pem"
    if not cert_path.exists():
        raise KeystoreError(f"{root}: no identity {name} (issue one with `stack keys issue {root} {name} --role ...`)")
    cert = x509.load_pem_x509_certificate(cert_path.read_bytes())
    roles = cert.subject.get_attributes_for_oid(NameOID.ORGANIZATIONAL_UNIT_NAME)
    sans = cert.extensions.get_extension_for_class(x509.SubjectAlternativeName).value
    names = tuple(str(n.value) for n in sans)
    role = str(roles[0].value) if roles else ""
    return Identity(name, role, cert.not_valid_after_utc, names, cert_path, cert_path.with_suffix(".key"))


def list_identities(root: Path) -> list[Identity]:
    _authority(root)
    return [read_identity(root, p.stem) for p in sorted((root / IDENTITIES).glob("*.pem"))]
