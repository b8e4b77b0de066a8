"""Counts the Cortex-M4 instructions one sample of each compensator executes, by emulating the
firmware image of examples/thumbv7em with the Unicorn engine (pip install unicorn).

    python tools/count_instructions.py IMAGE [SAMPLES]

The image's `_start` builds IHC, WIHC and DIHC (f32, ten operators, Table 1 and 2 of the paper)
and calls their step functions in turn on a triangle-wave trajectory; every instruction executed
between entering a step function and coming back to `_start` (callees included) is counted for
that compensator. The count is per sample, averaged over SAMPLES loop iterations (default 2000,
one period of the trajectory). Instructions, not cycles: on a Cortex-M4 most take one cycle,
loads and multiplies one or two, branches two to four, VDIV/VSQRT fourteen.
"""

import struct
import sys

from unicorn import UC_ARCH_ARM, UC_HOOK_CODE, UC_MODE_MCLASS, UC_MODE_THUMB, Uc
from unicorn import arm_const as arm


def load(image):
    """Segments and symbols of a 32-bit little-endian ARM ELF file."""
    data = open(image, "rb").read()
    assert data[:4] == b"\x7fELF" and data[4] == 1 and data[5] == 1, "a 32-bit little-endian ELF"
    (e_entry, e_phoff, e_shoff) = struct.unpack_from("<III", data, 24)
    (e_phentsize, e_phnum, e_shentsize, e_shnum, e_shstrndx) = struct.unpack_from("<HHHHH", data, 42)
    segments = []
    for i in range(e_phnum):
        p_type, p_offset, p_vaddr, _, p_filesz, p_memsz, _, _ = struct.unpack_from("<8I", data, e_phoff + i * e_phentsize)
        if p_type == 1:  # PT_LOAD
            segments.append((p_vaddr, data[p_offset : p_offset + p_filesz], p_memsz))
    sections = [struct.unpack_from("<10I", data, e_shoff + i * e_shentsize) for i in range(e_shnum)]
    symbols = {}
    for s in sections:
        if s[1] == 2:  # SHT_SYMTAB
            strtab = sections[s[6]]
            for k in range(s[5] // 16):
                name, value, size, info, _, _ = struct.unpack_from("<IIIBBH", data, s[4] + 16 * k)
                end = data.index(b"\0", strtab[4] + name)
                symbols[data[strtab[4] + name : end].decode()] = (value & ~1, size)
    return e_entry, segments, symbols


def main(argv):
    image = argv[1]
    samples = int(argv[2]) if len(argv) > 2 else 2000
    entry, segments, symbols = load(image)
    uc = Uc(UC_ARCH_ARM, UC_MODE_THUMB | UC_MODE_MCLASS)
    for vaddr, content, memsz in segments:
        base, top = vaddr & ~0xFFF, (vaddr + memsz + 0xFFF) & ~0xFFF
        uc.mem_map(base, top - base)
        uc.mem_write(vaddr, content)
    stack_top = 0x2008_0000
    uc.mem_map(stack_top - 0x10000, 0x10000)
    uc.reg_write(arm.UC_ARM_REG_SP, stack_top - 16)
    # Enable the FPU (CP10 and CP11 full access), as the reset code of a Cortex-M4F does.
    uc.mem_map(0xE000_0000, 0x10_0000)
    uc.mem_write(0xE000_ED88, struct.pack("<I", 0xF << 20))
    uc.reg_write(arm.UC_ARM_REG_FPEXC, 0x4000_0000)

    start, start_size = symbols["_start"]
    steps = {name: symbols[f"hystcomp_{name}_step"][0] for name in ("ihc", "wihc", "dihc")}
    entries = {address: name for name, address in steps.items()}
    counts = {name: 0 for name in steps}
    state = {"current": None, "loops": -1}

    def hook(uc, address, size, _):
        if start <= address < start + start_size:
            state["current"] = None
            return
        name = entries.get(address)
        if name is not None:
            state["current"] = name
            if name == "ihc":
                state["loops"] += 1
                if state["loops"] == samples:
                    uc.emu_stop()
                    return
        if state["current"] is not None and state["loops"] >= 0:
            counts[state["current"]] += 1

    uc.hook_add(UC_HOOK_CODE, hook)
    uc.emu_start(entry | 1, 0xFFFF_FFFF)
    for name, count in counts.items():
        print(f"{name}: {count / samples:.1f} instructions per sample (Cortex-M4, {samples} samples)")
    dac = next(value for name, (value, size) in symbols.items() if "DAC" in name and size == 12)
    outputs = struct.unpack("<3f", uc.mem_read(dac, 12))
    print("last outputs (ihc, wihc, dihc): " + " ".join(f"{v:.6f}" for v in outputs))


if __name__ == "__main__":
    main(sys.argv)
