// viewer_test.mjs - the page of `sem view` in headless Chromium, driven through chromedriver
// (Debian packages chromium and chromium-driver; WebDriver over HTTP, no npm package).
//
// usage: node viewer_test.mjs VIEWER.html SCREENSHOT_DIR
// Checks, exit 1 on the first failure:
//   - the page loads and draws the animation (window.semViewer.ready) with no console error
//     (browser log level SEVERE) and no error recorded by the page;
//   - a screenshot of the 3D view shows the object: pixels in the parts' colours (saturated;
//     the background, ground and shadow are grey) cover a plausible share of the view;
//   - the first and last frames differ: their object pixels are not the same set.
// Chromium runs headless as root (--no-sandbox) with software WebGL (SwiftShader), a fresh
// profile and no network services.
import { spawn } from 'node:child_process';
import { mkdtempSync, rmSync, writeFileSync } from 'node:fs';
import { createServer } from 'node:net';
import { tmpdir } from 'node:os';
import { join, resolve } from 'node:path';
import { inflateSync } from 'node:zlib';

const [page, shots] = process.argv.slice(2);
if (!page || !shots) {
  console.error('usage: node viewer_test.mjs VIEWER.html SCREENSHOT_DIR');
  process.exit(2);
}
const deadline = Date.now() + 90_000;
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
function fail(message) {
  console.error(`viewer_test: ${message}`);
  cleanup();
  process.exit(1);
}

// ---- PNG screenshots (8-bit RGB or RGBA, as Chromium writes them) ----
function decodePng(bytes) {
  if (bytes.readUInt32BE(0) !== 0x89504e47) throw new Error('not a PNG');
  let pos = 8, width = 0, height = 0, type = 0;
  const idat = [];
  while (pos < bytes.length) {
    const length = bytes.readUInt32BE(pos), kind = bytes.toString('latin1', pos + 4, pos + 8);
    const data = bytes.subarray(pos + 8, pos + 8 + length);
    if (kind === 'IHDR') {
      width = data.readUInt32BE(0);
      height = data.readUInt32BE(4);
      if (data[8] !== 8 || (data[9] !== 2 && data[9] !== 6) || data[12] !== 0) throw new Error('unsupported PNG');
      type = data[9];
    } else if (kind === 'IDAT') idat.push(data);
    pos += 12 + length;
  }
  const channels = type === 6 ? 4 : 3, stride = width * channels;
  const raw = inflateSync(Buffer.concat(idat));
  const out = Buffer.alloc(width * height * 3);
  let prev = Buffer.alloc(stride), cur = Buffer.alloc(stride);
  for (let y = 0; y < height; ++y) {
    const filter = raw[y * (stride + 1)];
    raw.copy(cur, 0, y * (stride + 1) + 1, (y + 1) * (stride + 1));
    for (let i = 0; i < stride; ++i) {
      const a = i >= channels ? cur[i - channels] : 0, b = prev[i], c = i >= channels ? prev[i - channels] : 0;
      let p = 0;
      if (filter === 1) p = a;
      else if (filter === 2) p = b;
      else if (filter === 3) p = (a + b) >> 1;
      else if (filter === 4) {
        const e = a + b - c, pa = Math.abs(e - a), pb = Math.abs(e - b), pc = Math.abs(e - c);
        p = pa <= pb && pa <= pc ? a : pb <= pc ? b : c;
      }
      cur[i] = (cur[i] + p) & 255;
    }
    for (let x = 0; x < width; ++x)
      for (let k = 0; k < 3; ++k) out[3 * (y * width + x) + k] = cur[x * channels + k];
    [prev, cur] = [cur, prev];
  }
  return { width, height, rgb: out };
}

// object pixels of a screenshot inside rect [x, y, w, h] (device pixels)
function objectMask(img, rect) {
  const [x0, y0, w, h] = rect.map(Math.round);
  const mask = new Uint8Array(w * h);
  let count = 0;
  for (let y = 0; y < h; ++y)
    for (let x = 0; x < w; ++x) {
      const p = 3 * ((y0 + y) * img.width + (x0 + x));
      const r = img.rgb[p], g = img.rgb[p + 1], b = img.rgb[p + 2];
      if (Math.max(r, g, b) - Math.min(r, g, b) > 45) {
        mask[y * w + x] = 1;
        ++count;
      }
    }
  return { mask, count, area: w * h };
}

// ---- chromedriver ----
let driver = null, session = null, profile = null, base = '';
function cleanup() {
  if (driver) driver.kill();
  if (profile) rmSync(profile, { recursive: true, force: true });
}
async function freePort() {
  return new Promise((done) => {
    const s = createServer();
    s.listen(0, '127.0.0.1', () => {
      const port = s.address().port;
      s.close(() => done(port));
    });
  });
}
async function call(method, path, body) {
  const response = await fetch(base + path, {
    method,
    headers: { 'content-type': 'application/json' },
    body: body === undefined ? undefined : JSON.stringify(body)
  });
  const json = await response.json();
  if (json.value && json.value.error) throw new Error(`${path}: ${json.value.message}`);
  return json.value;
}
const script = (code, ...args) => call('POST', `/session/${session}/execute/sync`, { script: code, args });

try {
  const port = await freePort();
  base = `http://127.0.0.1:${port}`;
  driver = spawn('chromedriver', [`--port=${port}`], { stdio: 'ignore' });
  driver.on('error', (e) => fail(`cannot start chromedriver: ${e.message}`));
  for (;;) {
    try {
      await call('GET', '/status');
      break;
    } catch (e) {
      if (Date.now() > deadline) fail('chromedriver did not start');
      await sleep(100);
    }
  }
  profile = mkdtempSync(join(tmpdir(), 'sem-chromium-'));
  const created = await call('POST', '/session', {
    capabilities: {
      alwaysMatch: {
        browserName: 'chrome',
        'goog:loggingPrefs': { browser: 'ALL' },
        'goog:chromeOptions': {
          binary: process.env.SEM_CHROMIUM || '/usr/bin/chromium',
          args: ['--headless=new', '--no-sandbox', '--disable-gpu', '--use-angle=swiftshader',
                 '--enable-unsafe-swiftshader', '--disable-quic', '--no-first-run',
                 '--disable-background-networking', '--disable-component-update', '--disable-sync',
                 '--disable-dev-shm-usage', '--window-size=1000,800', `--user-data-dir=${profile}`]
        }
      }
    }
  });
  session = created.sessionId;
  await call('POST', `/session/${session}/url`, { url: 'file://' + resolve(page) });
  let ready = false;
  while (!ready && Date.now() < deadline) {
    ready = await script('return !!(window.semViewer && (window.semViewer.ready || window.semViewer.errors.length));');
    if (!ready) await sleep(100);
  }
  const state = await script('return {ready: semViewer.ready, frames: semViewer.frameCount, errors: semViewer.errors};');
  if (!state.ready) fail(`the animation was not drawn: ${JSON.stringify(state.errors)}`);
  if (state.frames < 2) fail(`the page found ${state.frames} frames`);
  const rect = await script(`const r = document.querySelector('#view canvas').getBoundingClientRect();
                             const s = window.devicePixelRatio || 1;
                             return [r.left * s, r.top * s, r.width * s, r.height * s];`);
  const masks = [];
  for (const frame of [0, state.frames - 1]) {
    await script('semViewer.setFrame(arguments[0]);', frame);
    await sleep(200);
    const png = Buffer.from(await call('GET', `/session/${session}/screenshot`), 'base64');
    writeFileSync(join(shots, `viewer_frame_${frame}.png`), png);
    const m = objectMask(decodePng(png), rect);
    console.log(`frame ${frame}: object pixels ${m.count} of ${m.area} (${(100 * m.count / m.area).toFixed(1)}%)`);
    if (m.count < 0.01 * m.area || m.count > 0.6 * m.area)
      fail(`frame ${frame}: the object covers ${(100 * m.count / m.area).toFixed(2)}% of the view (expected 1-60%)`);
    masks.push(m);
  }
  let changed = 0;
  for (let i = 0; i < masks[0].mask.length; ++i) changed += masks[0].mask[i] !== masks[1].mask[i];
  console.log(`first and last frames differ in ${changed} pixels`);
  if (changed < 0.002 * masks[0].area) fail(`the first and last frames look the same (${changed} pixels differ)`);
  const log = await call('POST', `/session/${session}/se/log`, { type: 'browser' });
  const severe = log.filter((entry) => entry.level === 'SEVERE');
  for (const entry of log) console.log(`  console ${entry.level}: ${entry.message.slice(0, 300)}`);
  if (severe.length) fail(`${severe.length} console errors, first: ${severe[0].message}`);
  const errors = await script('return semViewer.errors;');
  if (errors.length) fail(`the page recorded errors: ${errors.join('; ')}`);
  await call('DELETE', `/session/${session}`);
  cleanup();
  console.log('viewer_test: ok');
} catch (e) {
  fail(e.stack || String(e));
}
