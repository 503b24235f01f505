"""The messages of syntax errors: what lark found and expected, named as the language
reference names it (a name, a number, a component TYPE:NAME), not as grammar terminals."""

from __future__ import annotations

import lark


def _describe_terminal(name: str, parser: lark.Lark) -> str:
    named = {
        "NAME": "a name",
        "NUMBER": "a number",
        "STRING": 'a "description"',
        "COMPONENT": "a component TYPE:NAME",
        "POW": "'^'",
        "_NL": "end of line",
        "$END": "end of file",
    }
    if name in named:
        return named[name]
    try:
        return repr(parser.get_terminal(name).pattern.value)
    except KeyError:
        return name


def syntax_message(exc: lark.exceptions.UnexpectedInput, parser: lark.Lark) -> str:
    """What a lark syntax error means, in the words of the language."""
    if isinstance(exc, lark.exceptions.UnexpectedCharacters):
        return f"unexpected character {exc.char!r}"
    if isinstance(exc, lark.exceptions.UnexpectedToken):
        token = exc.token
        found = (
            _describe_terminal(token.type, parser)
            if token.type in ("_NL", "$END")
            else repr(str(token))
        )
        if "COMPONENT" in exc.expected and "MODEL" in exc.expected:
            return (
                f"unexpected {found}; a statement is model, param, unknown, input, output,"
                " a component TYPE:NAME or a bond A -> B"
            )
        expected = sorted({_describe_terminal(t, parser) for t in exc.expected})
        return f"unexpected {found}; expected {' or '.join(expected)}"
    return "unexpected end of file"
