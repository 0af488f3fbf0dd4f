"""``certsolve schema robot``: print the JSON Schema of robot files."""

from __future__ import annotations

from ..robot.schema import robot_json_schema
from .common import print_json


def register(sub) -> None:
    p = sub.add_parser("schema", help="print the JSON Schema of an input format")
    p.add_argument("what", choices=["robot"], help="which format")
    p.set_defaults(func=run)


def run(args) -> int:
    print_json(robot_json_schema())
    return 0
