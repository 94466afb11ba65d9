// mesh_peer.mjs: runs a peer heightmap mesher for `tessera bench mesh
// --peers`, so that its meshes can be measured by tessera's own,
// independent measurement on the same input, on the same machine.
//
// Peers (npm packages, installed by tools/install-deps.sh into
// build/node_modules, or found in $TSR_NODE_MODULES; never vendored):
//   delatin         Garland-Heckbert greedy insertion on a Delaunay
//                   triangulation, a JavaScript port of hmm (C++)
//   @mapbox/martini right-triangulated irregular networks (RTIN)
//
// usage: node mesh_peer.mjs HEIGHTS.f64 WIDTH HEIGHT
// HEIGHTS.f64 holds WIDTH*HEIGHT little-endian doubles, row by row (the
// heights in output units). The script prints "ready" and then answers
// one command per line on stdin:
//   delatin E R OUT   mesh to max error E, best of R runs (R >= 1)
//   martini E R OUT   RTIN mesh at error parameter E; R >= 1 times
//                     createTile + getMesh (best of R), R = 0 reuses the
//                     last tile and is not timed
//   quit
// with "ok VERTICES TRIANGLES SECONDS LIVE_BYTES" (LIVE_BYTES: the heap
// and array buffers still held by the mesher after the run, after a
// garbage collection; 0 when node runs without --expose-gc) or
// "error MESSAGE". OUT gets the mesh: u32 vertex count, u32 triangle
// count, then x y per vertex (u32 sample column and row), then three u32
// vertex indices per triangle, in the machine's byte order.
import { readFileSync, writeFileSync } from 'node:fs';
import { createRequire } from 'node:module';
import { join } from 'node:path';
import { pathToFileURL } from 'node:url';
import { createInterface } from 'node:readline';
import { performance } from 'node:perf_hooks';

const [file, ws, hs] = process.argv.slice(2);
const width = Number(ws), height = Number(hs);
if (!file || !(width >= 2) || !(height >= 2)) {
    console.error('usage: node mesh_peer.mjs HEIGHTS.f64 WIDTH HEIGHT');
    process.exit(2);
}
const buf = readFileSync(file);
if (buf.length !== width * height * 8) {
    console.error(`${file}: ${buf.length} bytes, expected ${width * height * 8}`);
    process.exit(2);
}
const heights = new Float64Array(buf.buffer, buf.byteOffset, width * height);

// A package from $TSR_NODE_MODULES when set, else by node's own search
// (build/node_modules for the build tree's copy of this script); null
// when absent (reported per command).
async function load(name) {
    const dir = process.env.TSR_NODE_MODULES;
    if (dir) {
        try {
            const file = createRequire(join(dir, 'peer.js')).resolve(name);
            return (await import(pathToFileURL(file).href)).default;
        } catch (e) { /* try node's own search */ }
    }
    try {
        return (await import(name)).default;
    } catch (e) {
        return null;
    }
}
const Delatin = await load('delatin'), Martini = await load('@mapbox/martini');

function live() {
    if (typeof globalThis.gc !== 'function') return 0;
    globalThis.gc();
    const m = process.memoryUsage();
    return m.heapUsed + m.arrayBuffers;
}

// In the machine's byte order: tessera reads it on the same machine.
function writeMesh(out, nv, nt, vx, tri) {
    const a = new Uint32Array(2 + nv * 2 + nt * 3);
    a[0] = nv;
    a[1] = nt;
    a.set(vx, 2);
    a.set(tri, 2 + nv * 2);
    writeFileSync(out, new Uint8Array(a.buffer));
}

let tile = null, terrain32 = null; // the last martini tile (it keeps its Martini), the heights as floats

function run(cmd, e, r, out) {
    if (cmd === 'delatin') {
        if (!Delatin) throw new Error('npm package delatin not found (tools/install-deps.sh installs it in build/node_modules)');
        let best = Infinity, tin = null;
        const base = live();
        for (let k = 0; k < Math.max(r, 1); k++) {
            tin = null;
            const t0 = performance.now();
            tin = new Delatin(heights, width, height);
            tin.run(e);
            best = Math.min(best, (performance.now() - t0) / 1000);
        }
        const held = Math.max(live() - base, 0);
        writeMesh(out, tin.coords.length / 2, tin.triangles.length / 3, tin.coords, tin.triangles);
        return [tin.coords.length / 2, tin.triangles.length / 3, best, held];
    }
    if (cmd === 'martini') {
        if (!Martini) throw new Error('npm package @mapbox/martini not found (tools/install-deps.sh installs it in build/node_modules)');
        if (width !== height || ((width - 1) & (width - 2)) !== 0)
            throw new Error(`martini needs a (2^k+1)^2 grid, not ${width}x${height}`);
        if (!terrain32) terrain32 = Float32Array.from(heights);
        let best = 0, mesh = null;
        if (r > 0 || !tile) {
            best = Infinity;
            tile = null;
            for (let k = 0; k < Math.max(r, 1); k++) {
                const t0 = performance.now();
                tile = new Martini(width).createTile(terrain32);
                mesh = tile.getMesh(e);
                best = Math.min(best, (performance.now() - t0) / 1000);
            }
        } else
            mesh = tile.getMesh(e);
        const nv = mesh.vertices.length / 2, nt = mesh.triangles.length / 3;
        writeMesh(out, nv, nt, mesh.vertices, mesh.triangles);
        return [nv, nt, r > 0 ? best : 0, 0];
    }
    throw new Error(`unknown command ${cmd}`);
}

process.stdout.write('ready\n');
const rl = createInterface({ input: process.stdin, terminal: false });
for await (const line of rl) {
    const [cmd, es, rs, out] = line.trim().split(/\s+/);
    if (cmd === 'quit' || cmd === undefined) break;
    try {
        const e = Number(es), r = Number(rs);
        if (!(e >= 0) || !(r >= 0) || !out) throw new Error(`bad command '${line}'`);
        const [nv, nt, s, held] = run(cmd, e, r, out);
        process.stdout.write(`ok ${nv} ${nt} ${s} ${held}\n`);
    } catch (err) {
        process.stdout.write(`error ${String(err.message).replace(/\n/g, ' ')}\n`);
    }
}
