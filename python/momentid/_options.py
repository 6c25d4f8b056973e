"""The keyword arguments of identify() and select(), from the library's option table
(`_momentid._options(command)`, include/momentid/option_table.hpp): the signature and the
options part of the docstring are built from it at import, and the values go to the compiled
part, which turns each into its option's text and sets it as the command line does."""

from __future__ import annotations

import functools as _functools
import inspect as _inspect
import textwrap as _textwrap
from typing import Any, Mapping, Optional, Sequence, Union

from . import _momentid

# Monomials: a list (["y", "y*v^2"]) or the command line's list in one string ("y, y*v^2").
Monomials = Union[None, str, Sequence[str]]


def _takes_options(command: str):
    """Gives `function` (model, data, **options) the keyword arguments of `command` from the
    option table of the library (`_momentid._options(command)`): its signature lists them, its
    docstring's `<options>` describes them, and any other keyword raises TypeError."""

    table = _momentid._options(command)
    keywords = [option["keyword"] for option in table]

    def decorate(function):
        @_functools.wraps(function)
        def with_options(model, data, **options):
            for keyword in options:
                if keyword not in keywords:
                    raise TypeError(f"{function.__name__}() got an unexpected keyword argument "
                                    f"{keyword!r}")
            return function(model, data, **options)

        del with_options.__wrapped__  # the signature is the table's, below
        signature = _inspect.signature(function)
        leading = [p for p in signature.parameters.values() if p.kind != p.VAR_KEYWORD]
        with_options.__signature__ = signature.replace(parameters=leading + [
            _inspect.Parameter(option["keyword"], _inspect.Parameter.KEYWORD_ONLY,
                               default=False if option["value"] == "switch" else None,
                               annotation=_ANNOTATIONS[option["value"]])
            for option in table])
        with_options.__doc__ = function.__doc__.replace("<options>", _option_lines(table))
        return with_options

    return decorate


# The annotation of an option's keyword argument, by the kind of its value.
_ANNOTATIONS = {
    "count": Optional[int], "whole": Optional[int], "number": Optional[float],
    "text": Optional[str], "choice": Optional[str], "names": Union[None, str, Sequence[str]],
    "monomials": Monomials, "pairs": Optional[Mapping[str, Any]],
    "range": Optional[tuple[int, int]], "switch": bool, "size": Union[None, int, str],
    "record": Any,
}

# How a Python value is written for an option, by the kind of its value.
_VALUES = {
    "count": "int", "whole": "int", "number": "float", "text": "str", "choice": "str",
    "names": "a name or a list of names", "monomials": "monomials, a list or one string",
    "pairs": "{name: value}", "range": "(first, last)", "switch": "True or False",
    "size": "int or str such as '16M'", "record": "a path or a mapping of columns",
}


def _option_lines(table: list) -> str:
    """The options of a command as its docstring lists them, from the option table."""
    lines = []
    for option in table:
        value = _VALUES[option["value"]]
        if option["value"] == "choice":
            value = " | ".join(repr(c) for c in option["value_name"].split("|"))
        default = f"; default {option['default']}" if option["default"] else ""
        text = (f"{option['keyword']} ({value}{default}): {option['help']}, as "
                f"`{option['flag']} {option['value_name']}`.")
        lines += _textwrap.wrap(text, 96, initial_indent="    ", subsequent_indent="      ")
    return "\n".join(lines).strip()
