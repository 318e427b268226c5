"""Wheel–rail contact geometry: profiles, track, contact search, gaps."""

from .profiles import Profile, builtin_profile, read_profile

__all__ = ["Profile", "builtin_profile", "read_profile"]
