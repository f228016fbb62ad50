#!/usr/bin/env python3
"""Proves that a change to the PLY or VTP readers left what they read alone:
two builds read the same valid, truncated, byte-corrupted and fuzz-corpus
files (PLY binary little- and big-endian, fields, polygons, extra face
properties; VTP raw and zlib-compressed) and must agree on `keymesh check`
(exit code, stdout, stderr) and on the bytes of `keymesh convert` to .vtp.

    python3 scripts/same_reads.py --before /path/to/old/keymesh --after build/keymesh

Exits 1 and lists the files that differ; 0 when every file reads the same.
"""
import argparse, os, random, shutil, subprocess, glob, sys, struct, collections, tempfile
ap = argparse.ArgumentParser()
ap.add_argument("--before", required=True)
ap.add_argument("--after", required=True)
args = ap.parse_args()
old, new = os.path.abspath(args.before), os.path.abspath(args.after)
REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
W = tempfile.mkdtemp(prefix="same_reads_"); os.chdir(W)
random.seed(3)
subprocess.run([old, 'generate', 'sphere', '--size', '12', '-o', 's.vti', '-q'], check=True)
subprocess.run([old, 'contour', 's.vti', '--iso', '4.3', '-o', 'le.ply', '-q'], check=True)
subprocess.run([old, 'contour', 's.vti', '--iso', '4.3', '-o', 'f.vtp', '-q', '--normals', 'average', '--curvature'], check=True)
subprocess.run([old, 'convert', 'f.vtp', '-o', 'fields.ply', '-q'], check=True)
# a hand-made big-endian file with short indices, a quad, an extra face property and a double coordinate
def be_file():
    hdr = (b"ply\nformat binary_big_endian 1.0\nelement vertex 5\nproperty double x\nproperty float y\nproperty float z\n"
           b"property uchar red\nelement face 3\nproperty uchar flags\nproperty list uchar ushort vertex_indices\nproperty int tag\nend_header\n")
    body = b''
    for i in range(5): body += struct.pack('>dffB', i * 0.5, i % 2, (i * 7) % 3, i)
    for f in ([0, 1, 2], [1, 2, 3, 4], [2, 3, 4]): body += struct.pack('>BB', 9, len(f)) + b''.join(struct.pack('>H', v) for v in f) + struct.pack('>i', -4)
    return hdr + body
open('be.ply', 'wb').write(be_file())
def le_mixed():
    hdr = (b"ply\nformat binary_little_endian 1.0\nelement vertex 6\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\nproperty float nz\nproperty short q\n"
           b"element face 4\nproperty list int uint vertex_indices\nend_header\n")
    body = b''
    for i in range(6): body += struct.pack('<6fh', i, i * 2, -i, 0, 0, 1, -i)
    for f in ([0, 1, 2], [1, 2, 3, 4], [2, 3, 4], [0, 4, 5, 1, 3]): body += struct.pack('<i', len(f)) + b''.join(struct.pack('<I', v) for v in f)
    return hdr + body
open('lem.ply', 'wb').write(le_mixed())
subprocess.run([old, 'dual', 'le.ply', '-o', 'poly.vtp', '-q'], check=True)
files = ['le.ply', 'fields.ply', 'be.ply', 'lem.ply', 'f.vtp', 'poly.vtp']
for src in list(files):
    data = open(src, 'rb').read()
    hdr_end = data.index(b'end_header\n') + 11 if src.endswith('.ply') else max(0, data.find(b'<AppendedData'))
    for k in range(40):
        fn = f'trunc_{k}_{src}'; open(fn, 'wb').write(data[:random.randrange(hdr_end, len(data))]); files.append(fn)
    for k in range(120):
        b = bytearray(data)
        for _ in range(random.randint(1, 4)):
            b[random.randrange(hdr_end, len(b))] = random.choice([0, 1, 2, 3, 4, 5, 255, 0x80, 0x7f, 0xff, random.randrange(256)])
        fn = f'corrupt_{k}_{src}'; open(fn, 'wb').write(bytes(b)); files.append(fn)
    fn = f'trail_{src}'; open(fn, 'wb').write(data + b'\x01\x02\x03'); files.append(fn)
for f in glob.glob(os.path.join(REPO, 'tests/fuzz/**/*'), recursive=True):
    for ext in ('ply', 'vtp'):
        if os.path.isfile(f) and ext in f.lower():
            fn = 'c_' + f.replace('/', '_') + '.' + ext; open(fn, 'wb').write(open(f, 'rb').read()); files.append(fn)
diff = 0; codes = collections.Counter()
for fn in files:
    r = [subprocess.run([k, 'check', fn, '-q', '--threads', '2'], capture_output=True, text=True) for k in (old, new)]
    a = (r[0].returncode, r[0].stdout, r[0].stderr); b = (r[1].returncode, r[1].stdout, r[1].stderr)
    codes[r[1].returncode] += 1
    if a != b:
        diff += 1; print('DIFF', fn, a, b)
    o = [subprocess.run([k, 'convert', fn, '-o', f'{W}/out{i}.vtp', '-q'], capture_output=True, text=True) for i, k in enumerate((old, new))]
    if (o[0].returncode, o[0].stderr) != (o[1].returncode, o[1].stderr) or (o[0].returncode == 0 and open(f'{W}/out0.vtp', 'rb').read() != open(f'{W}/out1.vtp', 'rb').read()):
        diff += 1; print('CONVDIFF', fn, o[0].stderr, o[1].stderr)
    for i in (0, 1):
        if os.path.exists(f'{W}/out{i}.vtp'): os.remove(f'{W}/out{i}.vtp')
print(len(files), 'files,', diff, 'differ; exit codes of the new build', dict(codes))
os.chdir(REPO)
shutil.rmtree(W)
sys.exit(1 if diff else 0)
