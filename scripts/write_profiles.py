"""Write the built-in profiles to models/profiles/ as readable two-column files (mm).

Usage: python scripts/write_profiles.py
"""

from pathlib import Path

from railcontact.geometry.profiles import builtin_profile

OUT = Path(__file__).resolve().parents[1] / "models" / "profiles"

if __name__ == "__main__":
    for name in ("S1002", "60E1", "CN60"):
        print(builtin_profile(name).write(OUT / f"{name}.txt", unit="mm"))
