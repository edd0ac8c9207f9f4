#!/usr/bin/env python3
# Made slot_binary_v40.msh from slot_v40.msh: Gmsh 4.8 neither writes nor reads MSH 4.0 binary,
# so the fixture is converted here, with the layout of Gmsh 4.0's reader (msh_reader.cpp):
#   python3 msh40_to_binary.py slot_v40.msh slot_binary_v40.msh
import struct, sys
src, dst = sys.argv[1], sys.argv[2]
lines = open(src).read().split('\n')
out = bytearray()
i = 0
def sec(name):
    global i
    while lines[i] != name: i += 1
    i += 1
assert lines[0] == '$MeshFormat'
out += b'$MeshFormat\n4 1 8\n' + struct.pack('<i', 1) + b'\n$EndMeshFormat\n'
text = '\n'.join(lines)
if '$PhysicalNames' in lines:
    a = lines.index('$PhysicalNames'); b = lines.index('$EndPhysicalNames')
    out += ('\n'.join(lines[a:b+1]) + '\n').encode()
a = lines.index('$Entities'); b = lines.index('$EndEntities')
tok = ' '.join(lines[a+1:b]).split()
p = 0
def nxt():
    global p
    p += 1
    return tok[p-1]
out += b'$Entities\n'
counts = [int(nxt()) for _ in range(4)]
out += struct.pack('<4Q', *counts)
for d in range(4):
    for _ in range(counts[d]):
        out += struct.pack('<i', int(nxt()))
        out += struct.pack('<6d', *[float(nxt()) for _ in range(6)])
        n = int(nxt()); out += struct.pack('<Q', n); out += struct.pack('<%di' % n, *[int(nxt()) for _ in range(n)])
        if d > 0:
            n = int(nxt()); out += struct.pack('<Q', n); out += struct.pack('<%di' % n, *[int(nxt()) for _ in range(n)])
out += b'\n$EndEntities\n'
a = lines.index('$Nodes'); b = lines.index('$EndNodes')
tok = ' '.join(lines[a+1:b]).split(); p = 0
out += b'$Nodes\n'
nb, nn = int(nxt()), int(nxt()); out += struct.pack('<2Q', nb, nn)
for _ in range(nb):
    et, ed, par, n = int(nxt()), int(nxt()), int(nxt()), int(nxt())
    assert par == 0
    out += struct.pack('<3iQ', et, ed, par, n)
    for _ in range(n):
        out += struct.pack('<i3d', int(nxt()), float(nxt()), float(nxt()), float(nxt()))
out += b'\n$EndNodes\n'
a = lines.index('$Elements'); b = lines.index('$EndElements')
tok = ' '.join(lines[a+1:b]).split(); p = 0
out += b'$Elements\n'
nb, ne = int(nxt()), int(nxt()); out += struct.pack('<2Q', nb, ne)
nodes_of = {1: 2, 2: 3, 3: 4, 4: 4, 15: 1}
for _ in range(nb):
    et, ed, ty, n = int(nxt()), int(nxt()), int(nxt()), int(nxt())
    out += struct.pack('<3iQ', et, ed, ty, n)
    for _ in range(n):
        out += struct.pack('<%di' % (1 + nodes_of[ty]), *[int(nxt()) for _ in range(1 + nodes_of[ty])])
out += b'\n$EndElements\n'
open(dst, 'wb').write(out)
