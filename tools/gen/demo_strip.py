#!/usr/bin/env python3
"""Makes docs/images/demo.png, the README's picture: five of the demo's
renders (out/*.png, written by `cargo run --release -- demo`) scaled to one
height and set side by side.

Usage: python3 tools/gen/demo_strip.py [OUT_DIR] [PNG]   (needs Pillow: pip install pillow)
"""
import sys

from PIL import Image

SCENES = ["bubbles-noise", "absorbing-sphere", "gain-ring", "blue-gem", "two-layer-noise"]
HEIGHT = 220
GAP = 4


def main():
    src = sys.argv[1] if len(sys.argv) > 1 else "out"
    dst = sys.argv[2] if len(sys.argv) > 2 else "docs/images/demo.png"
    images = []
    for name in SCENES:
        im = Image.open(f"{src}/{name}.png").convert("RGB")
        width = round(im.width * HEIGHT / im.height)
        images.append(im.resize((width, HEIGHT), Image.LANCZOS))
    strip = Image.new("RGB", (sum(i.width for i in images) + GAP * (len(images) - 1), HEIGHT), "white")
    x = 0
    for im in images:
        strip.paste(im, (x, 0))
        x += im.width + GAP
    strip.save(dst, optimize=True)
    print(f"wrote {dst} ({strip.width} x {strip.height})")


if __name__ == "__main__":
    main()
