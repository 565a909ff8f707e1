#!/usr/bin/env python3
"""The instruction mix of the hottest functions of a callgrind profile.

    valgrind --tool=callgrind --dump-instr=yes --callgrind-out-file=cg.out <bench binary> robot mixed
    python3 shared/benches/instruction_mix.py cg.out <bench binary> [functions]

Callgrind counts every executed instruction exactly, whatever else the machine runs, but reports
them per source line; this sums them per machine instruction, reads each instruction's mnemonic from
`objdump -d` of the same binary, and prints, for the `functions` (default 6) functions with the most
executed instructions, how many fell in each class: vector loads and stores, vector arithmetic by
precision, shuffles and blends, conversions, scalar moves and address arithmetic, branches. Divided
by the link or voxel evaluations a pass ran (its steps times its links), the counts give
instructions per link. Functions are named by their address and symbol, since every `pulp`
dispatch shares one symbol.
"""
import collections
import re
import subprocess
import sys


def executed(profile):
    """Instructions executed per address. Callgrind writes addresses absolute (0x…), relative to
    the previous one (+n, -n) or the same (*); the cost line after a `calls=` line is the callee's
    inclusive cost and is not this instruction's."""
    counts = collections.Counter()
    last, after_call = 0, False
    for line in open(profile):
        if line.startswith("calls="):
            after_call = True
            continue
        if not line or not (line[0].isdigit() or line[0] in "+-*"):
            continue
        parts = line.split()
        token = parts[0]
        if token.startswith("0x"):
            address = int(token, 16)
        elif token == "*":
            address = last
        elif token[0] in "+-":
            step = int(token[1:], 16) if token[1:].startswith("0x") else int(token[1:])
            address = last + step if token[0] == "+" else last - step
        else:
            address = int(token)
        last = address
        if after_call:
            after_call = False
            continue
        if len(parts) >= 3:
            counts[address] += int(parts[2])
    return counts


def disassembly(binary):
    """Mnemonic, operands and enclosing function per address."""
    text = subprocess.run(
        ["objdump", "-d", "--no-show-raw-insn", "-C", binary], capture_output=True, text=True, check=True
    ).stdout
    function, instructions = None, {}
    for line in text.splitlines():
        if m := re.match(r"^([0-9a-f]+) <(.*)>:$", line):
            function = f"{m.group(1)[-6:]} {m.group(2)[:60]}"
        elif m := re.match(r"^\s+([0-9a-f]+):\s+(\S+)\s*(.*)$", line):
            instructions[int(m.group(1), 16)] = (m.group(2), m.group(3), function)
    return instructions


def kind(mnemonic, operands):
    if mnemonic.startswith("vgather"):
        return "vector gather"
    if mnemonic.startswith("v"):
        if mnemonic.startswith(("vmov", "vbroadcast", "vpbroadcast", "vlddqu")):
            return "vector load/store" if "(" in operands else "vector register move"
        if mnemonic.startswith(("vperm", "vshuf", "vunpck", "vinsert", "vextract", "vpshuf",
                                "vpunpck", "vblend", "vpblend", "vpalign")):
            return "vector shuffle/blend"
        if mnemonic.startswith("vcvt"):
            return "vector conversion"
        if re.match(r"v(add|sub|mul|div|sqrt|min|max|cmp|and|andn|or|xor|round)\w*p[sd]$", mnemonic):
            return "vector arithmetic " + mnemonic[-2:]
        return "vector other (scalar SSE, integer)"
    if mnemonic.startswith(("mov", "lea", "push", "pop")):
        return "scalar move/address"
    if mnemonic.startswith("j") or mnemonic in ("call", "ret", "cmp", "test"):
        return "branch/compare"
    return "scalar other"


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    counts = executed(sys.argv[1])
    instructions = disassembly(sys.argv[2])
    top = int(sys.argv[3]) if len(sys.argv) > 3 else 6
    per_function = collections.defaultdict(collections.Counter)
    for address, n in counts.items():
        if address in instructions:
            mnemonic, operands, function = instructions[address]
            per_function[function][kind(mnemonic, operands)] += n
    totals = sorted(per_function.items(), key=lambda item: -sum(item[1].values()))
    for function, classes in totals[:top]:
        total = sum(classes.values())
        print(f"{total:>15,}  {function}")
        for name, n in classes.most_common():
            print(f"{n:>15,}  {100 * n / total:5.1f} %  {name}")


if __name__ == "__main__":
    main()
