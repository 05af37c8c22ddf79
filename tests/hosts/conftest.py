"""Tests of one vehicle spread over several hosts, each a network namespace (tests/support/hosts.py)."""

from __future__ import annotations

from tests.support.hosts import network

__all__ = ["network"]
