"""Batched LAPACK calls that XLA:CPU may run at the same time (see
:mod:`moorjax.linalg.ordering`).

Reads the text of an optimised HLO module. In each computation, an instruction is
*hot* when it is a batched LAPACK/BLAS custom call (batch dimensions, all but the
last two of its first result, multiply to more than 1) or when it calls a
computation (while body and condition, conditional branches, call, fusion) that
holds one. Two hot instructions of one computation, neither of which reaches the
other through operands, are independent: XLA may run them at once.
"""

from __future__ import annotations

import itertools
import re

_INSTRUCTION = re.compile(r"^(?:ROOT\s+)?%?([\w.\-]+)\s*=\s*(.*)$")
_CALLED = re.compile(r"(?:calls|body|condition|to_apply|branch_computations|true_computation|"
                     r"false_computation)=\{?([%\w.\-, ]+)\}?")
_TARGET = re.compile(r'custom_call_target="([^"]+)"')
_SHAPE = re.compile(r"\w+\[([\d,]*)\]")


def _computations(text: str) -> dict[str, dict[str, str]]:
    """{computation: {instruction: its text after '='}}."""
    comps: dict[str, dict[str, str]] = {}
    current = None
    for line in text.splitlines():
        s = line.strip()
        head = s.split("(")[0]
        if s.endswith("{") and "->" in s and "=" not in head:
            name = s.split()[1] if s.startswith("ENTRY") else s.split()[0]
            current = comps.setdefault(name.lstrip("%"), {})
        elif s == "}":
            current = None
        elif current is not None and (m := _INSTRUCTION.match(s)):
            current[m.group(1)] = m.group(2)
    return comps


def batched_lapack(body: str) -> str | None:
    """The target of a batched LAPACK/BLAS custom call, else None."""
    target = _TARGET.search(body)
    if not target or not re.search(r"lapack|blas", target.group(1)):
        return None
    shape = _SHAPE.search(body)
    dims = [int(d) for d in shape.group(1).split(",") if d] if shape else []
    batch = 1
    for d in dims[:-2]:
        batch *= d
    return target.group(1) if batch > 1 else None


def concurrent_lapack(text: str) -> list[tuple[str, str, str]]:
    """(computation, instruction, instruction) for every pair of independent hot
    instructions in the module ``text``."""
    comps = _computations(text)
    memo: dict[str, bool] = {}

    def called(body):
        return [c.strip().lstrip("%") for group in _CALLED.findall(body) for c in group.split(",")]

    def holds(name, stack=()):
        if name not in memo:
            memo[name] = name in comps and name not in stack and any(
                batched_lapack(b) or any(holds(c, stack + (name,)) for c in called(b))
                for b in comps[name].values())
        return memo[name]

    pairs = []
    for cname, instrs in comps.items():
        operands = {i: {t for t in re.findall(r"%([\w.\-]+)", b) if t in instrs and t != i}
                    for i, b in instrs.items()}
        hot = [i for i, b in instrs.items() if batched_lapack(b) or any(holds(c) for c in called(b))]
        reach: dict[str, set[str]] = {}

        def upstream(i):
            if i not in reach:
                seen, todo = set(), list(operands[i])
                while todo:
                    j = todo.pop()
                    if j not in seen:
                        seen.add(j)
                        todo += operands[j]
                reach[i] = seen
            return reach[i]

        pairs += [(cname, a, b) for a, b in itertools.combinations(hot, 2)
                  if a not in upstream(b) and b not in upstream(a)]
    return pairs
