"""Screenshots of two pages of the built documentation site with headless Chromium
(Debian's ``chromium``), reduced to a 64-colour palette to stay small.

    python -m sphinx -W --keep-going -b html docs docs/_build/html
    python docs/render/site_screenshots.py      # writes docs/images/site/*.png

Runs Chromium headless with a fresh profile and without network features, as root
(``--no-sandbox``).
"""

from __future__ import annotations

import shutil
import subprocess
import tempfile
from pathlib import Path

from PIL import Image

DOCS = Path(__file__).resolve().parents[1]
HTML = DOCS / "_build" / "html"
OUT = DOCS / "images" / "site"
FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync",
         "--hide-scrollbars"]
#: (page, output name, window height, crop box (left, top, right, bottom) or None)
PAGES = [("from-liggghts.html", "from-liggghts.png", 1500, None),
         ("boundaries.html", "boundaries-pictures.png", 4200, (0, 1420, 1200, 2900))]


def shoot(page: str, name: str, height: int, crop) -> Path:
    chromium = shutil.which("chromium") or shutil.which("chromium-browser")
    if chromium is None:
        raise SystemExit("chromium not found (apt-get install -y chromium)")
    with tempfile.TemporaryDirectory() as profile:
        raw = Path(profile) / "shot.png"
        subprocess.run([chromium, *FLAGS, f"--user-data-dir={profile}/p",
                        f"--window-size=1200,{height}", f"--screenshot={raw}",
                        (HTML / page).as_uri()], check=True, capture_output=True, timeout=120)
        im = Image.open(raw).convert("RGB")
    if crop is not None:
        im = im.crop(crop)
    im = im.resize((im.size[0] * 3 // 4, im.size[1] * 3 // 4), Image.LANCZOS)
    path = OUT / name
    im.quantize(colors=64, method=Image.Quantize.MEDIANCUT).save(path, optimize=True)
    return path


def main() -> None:
    OUT.mkdir(parents=True, exist_ok=True)
    for page in PAGES:
        path = shoot(*page)
        print(f"wrote {path} ({path.stat().st_size // 1024} kB)")


if __name__ == "__main__":
    main()
