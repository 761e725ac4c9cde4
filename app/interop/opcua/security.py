"""Security of the desk's OPC UA server: its certificate, the endpoints offered, and
which client applications it trusts.

- The desk's application instance certificate (RSA 2048, self-signed, one year, its
  application URI and host name in subjectAltName) is created on first use in
  ``<pki>/own/`` (``cert.der``, ``key.pem``) by asyncua's helper, like the station key.
- Endpoints: Basic256Sha256 with SignAndEncrypt and with Sign. The None policy only
  when the site sets ``[opcua] allow_none_security`` (then logged as an error at start:
  everything, passwords aside, goes in clear text).
- Client certificates: trusted when their DER or PEM file is in ``trusted_dir``
  (default ``<pki>/trusted``; read at each new session, so an administrator's move
  takes effect without a restart). An unknown client is refused and its certificate
  written to ``<pki>/rejected/<thumbprint>.der`` for an administrator to move.
"""

from __future__ import annotations

import hashlib
import logging
import socket
from pathlib import Path
from typing import Any

from asyncua import Server, ua
from asyncua.common.utils import ServiceError
from asyncua.crypto.cert_gen import setup_self_signed_certificate
from asyncua.crypto.truststore import TrustStore
from asyncua.crypto.validator import CertificateValidator, CertificateValidatorOptions
from cryptography import x509
from cryptography.hazmat.primitives.serialization import Encoding
from cryptography.x509.oid import ExtendedKeyUsageOID

__all__ = ["APP_URI", "setup_security", "ClientTrust"]

log = logging.getLogger(__name__)

APP_URI = "urn:station-patrol:desk"
_CHECKS = (CertificateValidatorOptions.TIME_RANGE | CertificateValidatorOptions.URI
           | CertificateValidatorOptions.TRUSTED | CertificateValidatorOptions.PEER_CLIENT)


class ClientTrust:
    """asyncua's certificate validator on a folder of trusted certificates, reloaded
    for each session; an unknown certificate goes to ``rejected_dir``."""

    def __init__(self, trusted_dir: Path, rejected_dir: Path) -> None:
        self.trusted_dir, self.rejected_dir = trusted_dir, rejected_dir
        self.rejected = 0

    async def __call__(self, cert: x509.Certificate, app: ua.ApplicationDescription) -> None:
        try:
            if not any(self.trusted_dir.iterdir()):  # asyncua's store cannot be empty
                raise ServiceError(ua.StatusCodes.BadCertificateUntrusted)
            store = TrustStore([self.trusted_dir], [])
            await store.load()
            await CertificateValidator(_CHECKS, store)(cert, app)
        except Exception as e:
            self.rejected += 1
            der = cert.public_bytes(Encoding.DER)
            path = self.rejected_dir / f"{hashlib.sha1(der).hexdigest()}.der"  # noqa: S324
            self.rejected_dir.mkdir(parents=True, exist_ok=True)
            path.write_bytes(der)
            log.warning("OPC UA: client %s refused: its certificate is not trusted; written to "
                        "%s (move it to %s to trust it)", app.ApplicationUri, path,
                        self.trusted_dir)
            if isinstance(e, ServiceError):
                raise
            raise ServiceError(ua.StatusCodes.BadCertificateUntrusted) from e


async def setup_security(server: Server, settings: Any, pki_dir: Path, ruleset: Any) -> None:
    """Certificate, policies and client trust of ``server`` as the settings say."""
    own = pki_dir / "own"
    own.mkdir(parents=True, exist_ok=True)
    cert, key = own / "cert.der", own / "key.pem"
    if not cert.exists():
        log.info("OPC UA: creating the desk's certificate in %s", own)
    await setup_self_signed_certificate(key, cert, APP_URI, socket.gethostname(),
                                        [ExtendedKeyUsageOID.SERVER_AUTH,
                                         ExtendedKeyUsageOID.CLIENT_AUTH],
                                        {"commonName": "Station Patrol desk",
                                         "organizationName": "Station Patrol"})
    await server.load_certificate(str(cert))
    await server.load_private_key(str(key))
    policies = [ua.SecurityPolicyType.Basic256Sha256_SignAndEncrypt,
                ua.SecurityPolicyType.Basic256Sha256_Sign]
    if settings.allow_none_security:
        policies.append(ua.SecurityPolicyType.NoSecurity)
        log.error("OPC UA: SECURITY POLICY NONE IS ON ([opcua] allow_none_security): "
                  "data and commands travel unsigned and unencrypted")
    if settings.allow_anonymous:
        log.error("OPC UA: ANONYMOUS ACCESS IS ON ([opcua] allow_anonymous): anyone who "
                  "reaches the port reads the desk's data (as a viewer)")
    server.set_security_policy(policies, permission_ruleset=ruleset)
    trusted = Path(settings.trusted_dir) if settings.trusted_dir else pki_dir / "trusted"
    trusted.mkdir(parents=True, exist_ok=True)
    server.set_certificate_validator(ClientTrust(trusted, pki_dir / "rejected"))
