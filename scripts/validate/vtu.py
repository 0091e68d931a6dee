"""Reader for the VTK files cohdem writes (particles_*.vtu, walls_*.vtu: raw appended data
with UInt64 block headers, little-endian), standard library only: used by same_physics.py and
ring_shear_bed_case.py."""
import re, struct

_CODES = {"Float64": "d", "UInt64": "Q", "Int64": "q", "Int32": "i", "UInt8": "B"}


def read_arrays(path):
    """Every DataArray of the file: name -> list of values, or of tuples for several components."""
    b = open(path, "rb").read()
    i = b.index(b"<AppendedData")
    j = b.index(b"_", i) + 1
    hdr = b[:i].decode("latin1")
    out = {}
    for m in re.finditer(r'<DataArray type="(\w+)" Name="(\w+)" NumberOfComponents="(\d+)" format="appended" offset="(\d+)"', hdr):
        code, name, nc, off = _CODES[m.group(1)], m.group(2), int(m.group(3)), int(m.group(4))
        n = struct.unpack_from("<Q", b, j + off)[0] // struct.calcsize(code)
        v = struct.unpack_from("<%d%s" % (n, code), b, j + off + 8)
        out[name] = [v[k * nc:(k + 1) * nc] for k in range(n // nc)] if nc > 1 else list(v)
    return out
