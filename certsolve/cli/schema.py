"""``certsolve schema robot``: print the JSON Schema of robot files."""

from __future__ import annotations

from .common import print_json


def register(sub) -> None:
    p = sub.add_parser("schema")
    p.add_argument("what", choices=["robot"], help="which format")
    p.set_defaults(func=run)


def run(args) -> int:
    from ..robot.schema import robot_json_schema

    print_json(robot_json_schema())
    return 0
