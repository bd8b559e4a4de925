r"""Screenshot of a recording in a real rerun viewer at one state (docs/rerun_viewer.png), or of a
recording with no timeline (a grasp: ``mjtvm show --rrd``, docs/rerun_grasp.png).

Needs a display and a graphics adapter; without a GPU, Debian's ``xvfb`` and Mesa's
``lavapipe`` Vulkan driver (package ``mesa-vulkan-drivers``) do::

    mjtvm replay --rrd results/lift.rrd
    xvfb-run -a -s "-screen 0 1920x1200x24" python tools/rerun_screenshot.py \
        results/lift.rrd 25 docs/rerun_viewer.png
    mjtvm show case2 --rrd results/grasp.rrd
    xvfb-run -a -s "-screen 0 3400x1300x24" python tools/rerun_screenshot.py \
        results/grasp.rrd - docs/rerun_grasp.png

(a screen wider than twice the window keeps Xvfb's pointer, at the screen's centre, off the
viewer: no hover tooltip in the picture).

The viewer (``rerun.experimental.ViewerClient``, rerun 0.41) opens the file with its
blueprint, the time cursor is set to ``state`` = STATE (paused; ``-``: a static recording, no
cursor), and the whole window is saved
(1600 x 1000 px, the viewer's default window), then reduced to a 256-colour PNG.
"""

from __future__ import annotations

import argparse
import shutil
import sys
import tempfile
import time
from pathlib import Path

from PIL import Image
from rerun.experimental import ViewerClient


def main() -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("rrd", help="the recording (mjtvm replay --rrd)")
    parser.add_argument("state", help="state index to show, or - for a recording without a timeline")
    parser.add_argument("png", help="output image")
    parser.add_argument("--port", type=int, default=9877, help="viewer port (default 9877)")
    args = parser.parse_args()
    beside = Path(sys.executable).with_name("rerun")
    exe = str(beside) if beside.exists() else shutil.which("rerun")
    viewer = ViewerClient.spawn(
        port=args.port, detach_process=False, hide_welcome_screen=True, executable_path=exe
    )
    with tempfile.TemporaryDirectory() as tmp:
        raw = str(Path(tmp) / "raw.png")
        try:
            viewer.open(str(Path(args.rrd).resolve()))
            time.sleep(2.0)  # let the software rasterizer draw the first frames
            if args.state != "-":
                viewer.set_time("state", sequence=int(args.state), play_state="paused")
            time.sleep(2.0)
            viewer.save_screenshot(raw)
        finally:
            viewer.quit()
        Image.open(raw).convert("RGB").quantize(colors=256).save(args.png, optimize=True)
    print(f"wrote {args.png}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
