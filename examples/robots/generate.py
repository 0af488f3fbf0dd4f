"""Regenerate the bundled robot files from :mod:`certsolve.robot.presets`.

    python examples/robots/generate.py

The presets module documents every choice (Table I of Merlet 2007, the calibration of V and
L0 so that u = 0 in the middle of the workspace, Krut's motor angles).
"""

import json
import re
from pathlib import Path

from certsolve.robot.presets import all_presets

here = Path(__file__).parent
for name, spec in all_presets().items():
    text = json.dumps(spec, indent=2)
    # keep number lists on one line: [0.0, 60.0, 0.0]
    text = re.sub(
        r"\[\s+([-0-9.e,\s]+?)\s+\]",
        lambda m: "[" + ", ".join(v.strip() for v in m.group(1).split(",")) + "]",
        text,
    )
    (here / name).write_text(text + "\n")
    print("wrote", here / name)
