"""Whether a host names this machine only: the one loopback rule of every setting.

Decided from the text alone, with no name lookup, and narrow on purpose: each caller's other path is its safe
one (the MCP HTTP listener refuses to listen beyond loopback without authentication and TLS, the console
without TLS or ``--console-insecure``, a plain ``ws://`` robot URL off this machine gets a warning). So only
the canonical forms count:

* an IPv4 address in ``127.0.0.0/8``;
* ``::1``, bare or in brackets (``[::1]``, as in a URL), with or without a zone (``::1%lo``);
* the name ``localhost`` in any letter case (names are case-insensitive, and every resolver answers
  ``LOCALHOST`` from the same ``/etc/hosts`` line).

Not loopback: ``0.0.0.0`` and ``::`` (every interface), an empty host, any other address, IPv4-mapped
``::ffff:127.0.0.1`` (its ``is_loopback`` changed with Python 3.13; refused on every version here), short
forms such as ``127.1``, and every other name, even one that resolves to loopback: ``localhost.`` (an
absolute name some resolvers send to DNS), ``localhost.localdomain`` and ``*.localhost`` (loopback only where
``/etc/hosts`` or the resolver makes them so), the machine's own host name.
"""

from __future__ import annotations

import ipaddress

__all__ = ["is_loopback"]


def is_loopback(host: str) -> bool:
    """Whether *host* names this machine only (the module's rule)."""
    if host.startswith("[") and host.endswith("]"):
        try:
            address: ipaddress.IPv4Address | ipaddress.IPv6Address = ipaddress.IPv6Address(host[1:-1])
        except ValueError:
            return False
    elif host.lower() == "localhost":
        return True
    else:
        try:
            address = ipaddress.ip_address(host)
        except ValueError:
            return False
    if isinstance(address, ipaddress.IPv6Address) and address.ipv4_mapped is not None:
        return False
    return address.is_loopback
