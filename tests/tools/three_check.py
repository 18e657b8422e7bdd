#!/usr/bin/env python3
"""three_check.py GLB OURS.PNG CAMERA_LINE WORKDIR - cmz-view's picture against three.js's (issue 17).

The GLB that `cmz decode` wrote is loaded by three.js (Debian's libjs-three: three.min.js and its
GLTFLoader) in headless Chromium (Debian's, WebGL on SwiftShader) and drawn with the camera cmz-view
printed (`--camera`), each face in a colour of its own (its number, from the primitive's extras) and
unlit, antialiasing off.  Then, against cmz-view's PNG of the same model:
  - the silhouette masks (what is not background in each) must overlap with an intersection over
    union of at least 0.98;
  - in each face's region of three.js's picture (eroded by a pixel, at least 30 pixels, edge lines
    left out), the mean colour of cmz-view's pixels, as chromaticity (r, g, b) / (r + g + b), must
    be within 0.02 of the face's own colour's (the GLB material's, cmz-view's default steel grey
    for a face without one): the shading scales a colour, so its chromaticity stays.
This also proves the GLB loads in a real browser viewer.  Prints `iou X`, `faces N worst D` and
`ok` or the reasons, exit 0 when it passes, 1 when not, 2 when Chromium or three.js cannot run.
"""
import base64
import json
import os
import struct
import subprocess
import sys
import zlib

THREE = '/usr/share/javascript/three'
VIEW_DEFAULT_RGB = (0x9f, 0xb0, 0xc2)  # cm_view.c's colour for a face without one
EDGE_RGB = (0x1a, 0x1a, 0x1a)          # cm_view.c's edge and silhouette lines
IOU_MIN = 0.98
CHROMA_MAX = 0.02
REGION_MIN = 30


def read_png(path):
    d = open(path, 'rb').read()
    assert d[:8] == b'\x89PNG\r\n\x1a\n', path + ': not a PNG'
    at, idat, w, h, ctype, depth = 8, b'', 0, 0, 0, 0
    while at < len(d):
        n, t = struct.unpack('>I4s', d[at:at + 8])
        body = d[at + 8:at + 8 + n]
        if t == b'IHDR':
            w, h, depth, ctype = struct.unpack('>IIBB', body[:10])
        elif t == b'IDAT':
            idat += body
        at += 12 + n
    assert depth == 8 and ctype in (2, 6), '%s: colour type %d depth %d' % (path, ctype, depth)
    bpp = 3 if ctype == 2 else 4
    raw = zlib.decompress(idat)
    stride = w * bpp
    out = bytearray(w * h * 3)
    prev = bytearray(stride)
    for y in range(h):
        f = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):  # PNG filters (Chromium's PNGs use them; cmz-view's are unfiltered)
            a = line[i - bpp] if i >= bpp else 0
            b = prev[i]
            c = prev[i - bpp] if i >= bpp else 0
            if f == 1:
                line[i] = (line[i] + a) & 255
            elif f == 2:
                line[i] = (line[i] + b) & 255
            elif f == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else (b if pb <= pc else c))) & 255
        for x in range(w):
            out[3 * (y * w + x):3 * (y * w + x) + 3] = line[bpp * x:bpp * x + 3]
        prev = line
    return w, h, out


def glb_face_colours(glb):
    """face number -> (r, g, b) 0..255 as cmz-view draws it, from the GLB's materials"""
    n = struct.unpack('<I', glb[12:16])[0]
    j = json.loads(glb[20:20 + n])
    mats = j.get('materials', [])
    colours = {}
    for mesh in j.get('meshes', []):
        for prim in mesh.get('primitives', []):
            face = prim.get('extras', {}).get('face')
            m = prim.get('material')
            if face is None:
                continue
            # the writer's materials: one per distinct colour, the default grey last (cm_glb.c)
            if m is None or (m == len(mats) - 1 and mats[m]['pbrMetallicRoughness']['baseColorFactor'][:3] == [0.8, 0.8, 0.8]):
                colours[face] = VIEW_DEFAULT_RGB
            else:
                c = mats[m]['pbrMetallicRoughness']['baseColorFactor']
                colours[face] = tuple(int(round(255 * v)) for v in c[:3])
    return colours


PAGE = '''<html><body style="margin:0;background:#ffffff">
<script src="file://%(three)s/three.min.js"></script>
<script src="file://%(three)s/examples/js/loaders/GLTFLoader.js"></script>
<script>
const cam = %(cam)s;
const bytes = Uint8Array.from(atob("%(glb)s"), c => c.charCodeAt(0));
const renderer = new THREE.WebGLRenderer({antialias: false, preserveDrawingBuffer: true});
renderer.setPixelRatio(1);
renderer.setSize(cam.W, cam.H);
renderer.setClearColor(0xffffff, 1);
document.body.appendChild(renderer.domElement);
/* CAD millimetres, Z up -> glTF metres, Y up: (x, y, z) -> 0.001 (x, z, -y) (cm_glb.c's root node) */
const gl = p => new THREE.Vector3(p[0], p[2], -p[1]);
new THREE.GLTFLoader().parse(bytes.buffer, '', gltf => {
  gltf.scene.traverse(o => {
    if (!o.isMesh) return;
    const id = (o.geometry.userData.face | 0) + 1;
    o.material = new THREE.MeshBasicMaterial({side: THREE.DoubleSide,
      color: new THREE.Color(((id >> 16) & 255) / 255, ((id >> 8) & 255) / 255, (id & 255) / 255)});
  });
  const box = new THREE.Box3().setFromObject(gltf.scene);
  const D = 4 * box.getSize(new THREE.Vector3()).length() + 1;
  const s = cam.scale * 1000; /* pixels per metre */
  const C = gl(cam.c).multiplyScalar(0.001), F = gl(cam.f).normalize(), U = gl(cam.u).normalize();
  const camera = new THREE.OrthographicCamera(-cam.W / 2 / s, cam.W / 2 / s, cam.H / 2 / s, -cam.H / 2 / s, 0, 2 * D);
  camera.position.copy(C).addScaledVector(F, -D);
  camera.up.copy(U);
  camera.lookAt(C);
  camera.updateProjectionMatrix();
  renderer.render(gltf.scene, camera);
  document.title = 'drawn';
}, err => { document.title = 'error ' + err; });
</script></body></html>
'''


def main():
    glb_path, ours_path, camera_line, work = sys.argv[1:5]
    f = camera_line.split()
    if len(f) != 17 or f[0] != 'camera':
        print('cannot read the camera line: %r' % camera_line)
        return 1
    W, H = int(f[1]), int(f[2])
    v = [float(x) for x in f[3:]]
    if v[1] != 0.0:
        print('a perspective camera: only orthographic views are compared')
        return 1
    cam = {'W': W, 'H': H, 'scale': v[0], 'c': v[2:5], 'r': v[5:8], 'u': v[8:11], 'f': v[11:14]}
    glb = open(glb_path, 'rb').read()
    page = os.path.join(work, 'three.html')
    shot = os.path.join(work, 'three.png')
    with open(page, 'w') as out:
        out.write(PAGE % {'three': THREE, 'cam': json.dumps(cam), 'glb': base64.b64encode(glb).decode()})
    if os.path.exists(shot):
        os.remove(shot)
    cmd = ['chromium', '--headless=new', '--no-sandbox', '--disable-gpu-sandbox', '--use-angle=swiftshader',
           '--enable-unsafe-swiftshader', '--allow-file-access-from-files', '--hide-scrollbars',
           '--force-device-scale-factor=1', '--virtual-time-budget=20000', '--window-size=%d,%d' % (W, H),
           '--screenshot=' + shot, 'file://' + page]
    try:
        r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=120)
    except (OSError, subprocess.TimeoutExpired) as e:
        print('chromium did not run: %s' % e)
        return 2
    if not os.path.exists(shot):
        print('chromium wrote no screenshot: %s' % r.stdout.decode(errors='replace')[-400:])
        return 2
    w1, h1, ours = read_png(ours_path)
    w2, h2, three = read_png(shot)
    if (w1, h1) != (W, H) or (w2, h2) != (W, H):
        print('sizes differ: cmz-view %dx%d, three.js %dx%d, camera %dx%d' % (w1, h1, w2, h2, W, H))
        return 1
    n = W * H
    ids = [0] * n
    inter = union = 0
    for i in range(n):
        o = ours[3 * i:3 * i + 3] != b'\xff\xff\xff'
        t3 = three[3 * i:3 * i + 3]
        t = t3 != b'\xff\xff\xff'
        ids[i] = (t3[0] << 16 | t3[1] << 8 | t3[2]) if t else 0
        inter += o and t
        union += o or t
    iou = inter / union if union else 0.0
    print('iou %.4f (cmz-view %d pixels, three.js %d)' % (iou, sum(1 for i in range(n) if ours[3 * i:3 * i + 3] != b'\xff\xff\xff'),
                                                        sum(1 for i in range(n) if ids[i])))
    colours = glb_face_colours(glb)
    sums = {}
    for y in range(1, H - 1):
        for x in range(1, W - 1):
            i = y * W + x
            k = ids[i]
            if k == 0 or ids[i - 1] != k or ids[i + 1] != k or ids[i - W] != k or ids[i + W] != k:
                continue
            p = tuple(ours[3 * i:3 * i + 3])
            if p == EDGE_RGB or p == (255, 255, 255) or sum(p) == 0:
                continue
            s = sums.setdefault(k - 1, [0.0, 0.0, 0.0, 0])
            t = float(sum(p))
            s[0] += p[0] / t
            s[1] += p[1] / t
            s[2] += p[2] / t
            s[3] += 1
    worst, worst_face, faces = 0.0, None, 0
    for face, s in sums.items():
        if s[3] < REGION_MIN or face not in colours:
            continue
        faces += 1
        c = colours[face]
        ct = float(sum(c)) or 1.0
        d = max(abs(s[j] / s[3] - c[j] / ct) for j in range(3))
        if d > worst:
            worst, worst_face = d, face
    print('faces %d worst %.4f%s' % (faces, worst, ' (face %d)' % worst_face if worst_face is not None else ''))
    bad = []
    if iou < IOU_MIN:
        bad.append('silhouettes overlap %.4f < %.2f' % (iou, IOU_MIN))
    if faces == 0:
        bad.append('no face region to compare')
    if worst > CHROMA_MAX:
        bad.append('face %d colour off by %.4f > %.2f' % (worst_face, worst, CHROMA_MAX))
    print('ok' if not bad else 'not ok: ' + '; '.join(bad))
    return 0 if not bad else 1


if __name__ == '__main__':
    sys.exit(main())
