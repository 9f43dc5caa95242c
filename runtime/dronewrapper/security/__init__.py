"""Security: the project's keys, Zenoh mTLS identities, access control, the command lease.

Submodules import ``cryptography`` only where certificates are made (``keystore``), so the SDK
without the ``security`` extra still connects with an existing identity.
"""
