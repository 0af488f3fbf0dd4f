"""Minibex tokens, the parse error, and the size limits of the parser (one place for all).

Comments are ``// ...``, ``# ...`` (to the end of the line) and ``/* ... */``.  Numbers are
decimal literals (``2``, ``1.5``, ``.5``, ``1.``, ``1e-3``, ``1.e-3``); they stay exact
(:class:`fractions.Fraction`) until they meet a non-exact operation.  Every token carries its
line and column, and every error names them.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

__all__ = ["MinibexError", "Limits", "LIMITS", "Token", "tokenize"]


class MinibexError(ValueError):
    """A syntax or semantic error in a Minibex text, with its position (1-based)."""

    def __init__(self, message: str, line: int, col: int):
        super().__init__(f"line {line}, column {col}: {message}")
        self.line = line
        self.col = col
        self.reason = message


@dataclass(frozen=True, kw_only=True)
class Limits:
    """Bounds on what one Minibex text may ask of the parser (the CLI and HTTP share them).

    ``max_depth`` bounds the nesting of expressions (parentheses, unary signs, powers, function
    calls): the parser is recursive-descent, and this keeps it far from Python's recursion
    limit.  ``max_work`` bounds the tokens read, loop bodies and inlined functions counted once
    per expansion, so that ``for i=1:1e9`` or nested function calls cannot run away.
    """

    max_chars: int = 2_000_000
    max_depth: int = 100
    max_work: int = 5_000_000
    max_variables: int = 100_000
    max_dim: int = 1_000_000  # components of one vector / matrix


LIMITS = Limits()


@dataclass(frozen=True)
class Token:
    kind: str  # NUM, ID, OP, EOF
    text: str
    line: int
    col: int

    def after(self) -> Token:
        """A position just after this token (where a missing ';' belongs)."""
        return Token(self.kind, self.text, self.line, self.col + len(self.text))


_TOKEN_RE = re.compile(
    r"""
    (?P<ws>[ \t\r\f\v]+)
  | (?P<nl>\n)
  | (?P<comment>(?://|\#)[^\n]*)
  | (?P<block>/\*)
  | (?P<num>(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)
  | (?P<id>[A-Za-z_][A-Za-z_0-9]*)
  | (?P<op>==|<=|>=|:=|[-+*/^()\[\],;=<>:'])
    """,
    re.VERBOSE,
)


def tokenize(text: str, limits: Limits = LIMITS) -> list[Token]:
    """The tokens of ``text``, ending with an ``EOF`` token."""
    if len(text) > limits.max_chars:
        raise MinibexError(f"the text has {len(text)} characters; at most {limits.max_chars}", 1, 1)
    toks: list[Token] = []
    pos, line, line_start = 0, 1, 0
    n = len(text)
    while pos < n:
        m = _TOKEN_RE.match(text, pos)
        col = pos - line_start + 1
        if not m:
            raise MinibexError(f"unexpected character {text[pos]!r}", line, col)
        kind = m.lastgroup
        end = m.end()
        if kind == "nl":
            line += 1
            line_start = end
        elif kind == "block":
            close = text.find("*/", end)
            if close < 0:
                raise MinibexError("unterminated comment '/*'", line, col)
            body = text[pos:close]
            nls = body.count("\n")
            if nls:
                line += nls
                line_start = pos + body.rfind("\n") + 1
            end = close + 2
        elif kind == "num":
            toks.append(Token("NUM", m.group(), line, col))
        elif kind == "id":
            toks.append(Token("ID", m.group(), line, col))
        elif kind == "op":
            toks.append(Token("OP", m.group(), line, col))
        pos = end
    toks.append(Token("EOF", "", line, pos - line_start + 1))
    return toks
