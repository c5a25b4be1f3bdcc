#!/usr/bin/env python3
"""The README's picture of the workbench, rendered from the real screen.

Opens `quadcl` (no arguments: the workbench on the shipped run, as a new user
sees it) in a detached tmux session of 120 x 40 cells, waits until the first
screen has drawn and stopped changing, optionally sends keys, captures the
pane with its colours (`tmux capture-pane -e -p`: text with ANSI escapes) and
draws every cell with its foreground and background colour into a PNG.

    python3 scripts/screenshot.py [--out docs/workbench.png] [--keys KEY ...]
                                  [--bin target/release/quadcl] [--ansi FILE]

The workbench runs in a temporary folder whose `scenes/` and `policies/` link
to the repository's, so it opens `runs/workbench` there (the path the screen
shows a user) and nothing is written into the checkout. `--ansi FILE` renders a
capture saved before instead of running the workbench.

Needs tmux, Pillow (`pip install pillow`) and DejaVu Sans Mono (Debian:
`apt-get install fonts-dejavu-core`). Not part of CI.
"""

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
COLS, ROWS = 120, 40
FONT_PATHS = [
    "/usr/share/fonts/truetype/dejavu/DejaVuSansMono.ttf",
    "/usr/share/fonts/TTF/DejaVuSansMono.ttf",
    "/Library/Fonts/DejaVuSansMono.ttf",
]
BOLD_FONT_PATHS = [p.replace("DejaVuSansMono.ttf", "DejaVuSansMono-Bold.ttf") for p in FONT_PATHS]

# A dark terminal: the default colours and the 16 named ones (xterm's values, a little softened).
DEFAULT_FG = (220, 220, 220)
DEFAULT_BG = (24, 24, 28)
NAMED = [
    (0, 0, 0), (205, 49, 49), (13, 188, 121), (229, 229, 16),
    (36, 114, 200), (188, 63, 188), (17, 168, 205), (204, 204, 204),
    (118, 118, 118), (241, 76, 76), (35, 209, 139), (245, 245, 67),
    (59, 142, 234), (214, 112, 214), (41, 184, 219), (242, 242, 242),
]


def xterm256(n):
    """The RGB of xterm's 256-colour palette entry n."""
    if n < 16:
        return NAMED[n]
    if n < 232:
        n -= 16
        steps = [0, 95, 135, 175, 215, 255]
        return (steps[n // 36], steps[(n // 6) % 6], steps[n % 6])
    v = 8 + 10 * (n - 232)
    return (v, v, v)


class Cell:
    __slots__ = ("ch", "fg", "bg", "bold", "dim", "reverse", "underline")

    def __init__(self):
        self.ch, self.fg, self.bg = " ", None, None
        self.bold = self.dim = self.reverse = self.underline = False


def parse(text):
    """ANSI text (one line per row) to a grid of cells. Handles SGR escapes only."""
    grid = [[Cell() for _ in range(COLS)] for _ in range(ROWS)]
    state = Cell()
    for row, line in enumerate(text.split("\n")[:ROWS]):
        col = 0
        i = 0
        while i < len(line):
            m = re.match(r"\x1b\[([0-9;:]*)m", line[i:])
            if m:
                sgr(state, m.group(1))
                i += m.end()
                continue
            if line[i] == "\x1b":  # another escape: skip it
                m = re.match(r"\x1b\[[0-9;?]*[A-Za-z]|\x1b.", line[i:])
                i += m.end() if m else 1
                continue
            if col < COLS:
                c = grid[row][col]
                c.ch, c.fg, c.bg = line[i], state.fg, state.bg
                c.bold, c.dim, c.reverse, c.underline = state.bold, state.dim, state.reverse, state.underline
            col += 1
            i += 1
    return grid


def sgr(state, params):
    codes = [int(p) if p else 0 for p in re.split("[;:]", params)] if params else [0]
    i = 0
    while i < len(codes):
        c = codes[i]
        if c == 0:
            state.fg = state.bg = None
            state.bold = state.dim = state.reverse = state.underline = False
        elif c == 1:
            state.bold = True
        elif c == 2:
            state.dim = True
        elif c == 4:
            state.underline = True
        elif c == 7:
            state.reverse = True
        elif c == 22:
            state.bold = state.dim = False
        elif c == 24:
            state.underline = False
        elif c == 27:
            state.reverse = False
        elif 30 <= c <= 37:
            state.fg = NAMED[c - 30]
        elif 90 <= c <= 97:
            state.fg = NAMED[c - 90 + 8]
        elif 40 <= c <= 47:
            state.bg = NAMED[c - 40]
        elif 100 <= c <= 107:
            state.bg = NAMED[c - 100 + 8]
        elif c == 39:
            state.fg = None
        elif c == 49:
            state.bg = None
        elif c in (38, 48) and i + 1 < len(codes):
            if codes[i + 1] == 5 and i + 2 < len(codes):
                rgb = xterm256(codes[i + 2])
                i += 2
            elif codes[i + 1] == 2 and i + 4 < len(codes):
                rgb = tuple(codes[i + 2 : i + 5])
                i += 4
            else:
                rgb = None
            if c == 38:
                state.fg = rgb
            else:
                state.bg = rgb
        i += 1


# Box-drawing characters drawn as lines (so they join across cells): (up, down, left, right).
BOX = {
    "─": (0, 0, 1, 1), "│": (1, 1, 0, 0), "┌": (0, 1, 0, 1), "┐": (0, 1, 1, 0),
    "└": (1, 0, 0, 1), "┘": (1, 0, 1, 0), "├": (1, 1, 0, 1), "┤": (1, 1, 1, 0),
    "┬": (0, 1, 1, 1), "┴": (1, 0, 1, 1), "┼": (1, 1, 1, 1),
}


# Braille dot n (bit n of the code point's offset from U+2800) at (column, row) of the 2 x 4 grid.
BRAILLE = [(0, 0), (0, 1), (0, 2), (1, 0), (1, 1), (1, 2), (0, 3), (1, 3)]


def render(grid, out):
    from PIL import Image, ImageDraw, ImageFont

    font_path = next((p for p in FONT_PATHS if os.path.exists(p)), None)
    if font_path is None:
        sys.exit("screenshot: DejaVu Sans Mono not found (apt-get install fonts-dejavu-core)")
    bold_path = next((p for p in BOLD_FONT_PATHS if os.path.exists(p)), font_path)
    size = 15
    font = ImageFont.truetype(font_path, size)
    bold = ImageFont.truetype(bold_path, size)
    cw = round(font.getlength("M"))
    ascent, descent = font.getmetrics()
    ch = ascent + descent
    pad = 10
    img = Image.new("RGB", (COLS * cw + 2 * pad, ROWS * ch + 2 * pad), DEFAULT_BG)
    draw = ImageDraw.Draw(img)
    for r, row in enumerate(grid):
        for c, cell in enumerate(row):
            fg = cell.fg or DEFAULT_FG
            bg = cell.bg or DEFAULT_BG
            if cell.reverse:
                fg, bg = bg, fg
            if cell.dim:
                fg = tuple((a + b) // 2 for a, b in zip(fg, bg))
            x, y = pad + c * cw, pad + r * ch
            draw.rectangle([x, y, x + cw - 1, y + ch - 1], fill=bg)
            g = cell.ch
            if g == " ":
                pass
            elif g == "█":
                draw.rectangle([x, y, x + cw - 1, y + ch - 1], fill=fg)
            elif g == "▀":
                draw.rectangle([x, y, x + cw - 1, y + ch // 2 - 1], fill=fg)
            elif g == "▄":
                draw.rectangle([x, y + ch // 2, x + cw - 1, y + ch - 1], fill=fg)
            elif 0x2800 <= ord(g) <= 0x28FF:  # braille: 2 x 4 dots (not in DejaVu Sans Mono)
                bits = ord(g) - 0x2800
                for bit, (dx, dy) in enumerate(BRAILLE):
                    if bits >> bit & 1:
                        px, py = x + cw * (1 + 2 * dx) // 4, y + ch * (1 + 2 * dy) // 8
                        draw.rectangle([px - 1, py - 1, px + 1, py + 1], fill=fg)
            elif g in BOX:
                up, down, left, right = BOX[g]
                mx, my = x + cw // 2, y + ch // 2
                if left:
                    draw.line([x, my, mx, my], fill=fg)
                if right:
                    draw.line([mx, my, x + cw - 1, my], fill=fg)
                if up:
                    draw.line([mx, y, mx, my], fill=fg)
                if down:
                    draw.line([mx, my, mx, y + ch - 1], fill=fg)
            else:
                draw.text((x, y), g, font=bold if cell.bold else font, fill=fg)
            if cell.underline:
                draw.line([x, y + ch - 2, x + cw - 1, y + ch - 2], fill=fg)
    img.save(out, optimize=True)


def tmux(*args):
    return subprocess.run(["tmux", *args], check=True, capture_output=True, text=True).stdout


def capture(binary, keys):
    if shutil.which("tmux") is None:
        sys.exit("screenshot: tmux is not installed (apt-get install tmux)")
    tmp = tempfile.mkdtemp(prefix="quadcl-shot-")
    session = f"quadcl-shot-{os.getpid()}"
    try:
        for d in ("scenes", "policies"):
            os.symlink(os.path.join(ROOT, d), os.path.join(tmp, d))
        cmd = f"cd {tmp} && {binary} 2>{tmp}/stderr; sleep 30"
        tmux("new-session", "-d", "-s", session, "-x", str(COLS), "-y", str(ROWS), cmd)

        def pane():
            return tmux("capture-pane", "-p", "-e", "-t", session)

        deadline = time.time() + 120
        last, stable_since = None, time.time()
        # Until the first screen shows and has not changed for 2 s (the curves load after it opens).
        while True:
            text = pane()
            if text != last:
                last, stable_since = text, time.time()
            elif "Sequence" in text and time.time() - stable_since > 2:
                break
            if time.time() > deadline:
                err = open(os.path.join(tmp, "stderr")).read() if os.path.exists(os.path.join(tmp, "stderr")) else ""
                sys.exit(f"screenshot: the workbench did not settle:\n{re.sub(chr(27) + r'[^m]*m', '', text)}\n{err}")
            time.sleep(0.2)
        for key in keys:
            tmux("send-keys", "-t", session, key)
            time.sleep(1.0)
        time.sleep(1.0)
        return pane()
    finally:
        subprocess.run(["tmux", "kill-session", "-t", session], capture_output=True)
        shutil.rmtree(tmp, ignore_errors=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", default=os.path.join(ROOT, "docs", "workbench.png"))
    ap.add_argument("--bin", default=os.environ.get("QUADCL_BIN", os.path.join(ROOT, "target", "release", "quadcl")))
    ap.add_argument("--keys", nargs="*", default=[], help="tmux key names sent after the first screen, e.g. Up 2")
    ap.add_argument("--ansi", help="render this saved capture instead of running the workbench")
    ap.add_argument("--save-ansi", help="also keep the capture (ANSI text) in this file")
    a = ap.parse_args()
    if a.ansi:
        text = open(a.ansi, encoding="utf-8").read()
    else:
        if not os.access(a.bin, os.X_OK):
            subprocess.run(["cargo", "build", "--release", "--bin", "quadcl"], cwd=ROOT, check=True)
        text = capture(os.path.abspath(a.bin), a.keys)
    if a.save_ansi:
        open(a.save_ansi, "w", encoding="utf-8").write(text)
    render(parse(text), a.out)
    print(f"wrote {a.out}")


if __name__ == "__main__":
    main()
