// Browser test of the ground station page in real headless Chromium (Debian's /usr/bin/chromium,
// driven by playwright-core). Starts the stand-in vehicle (ground_station_fixture) and the real
// alight-ground-station on a private LCM URL, then checks that the page loads, video frames
// arrive and change, the phase shown follows AUTONOMY_STATUS, and clicking "go" (plus the
// keyboard abort and the confirmed kill) puts correctly signed OPERATOR_CMD messages on LCM, as
// judged by CommandVerifier in the fixture. Saves a screenshot as an artifact.
//
// usage: node browser_test.mjs --station BIN --fixture BIN --out DIR [--lcm-url URL]
// exit: 0 pass, 1 fail, 77 skipped (playwright-core or chromium not installed)

import { spawn } from 'node:child_process';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import readline from 'node:readline';

const SKIP = 77;
const CHROMIUM = '/usr/bin/chromium';
const args = Object.fromEntries(
  process.argv.slice(2).reduce((acc, a, i, all) => (a.startsWith('--') ? [...acc, [a.slice(2), all[i + 1]]] : acc), []));
const lcmUrl = args['lcm-url'] || 'udpm://239.255.76.67:7861?ttl=0';
const outDir = args.out || '.';
const deadline = Date.now() + 75_000;  // the whole test, whatever happens

let chromium;
try {
  ({ chromium } = await import('playwright-core'));
} catch (e) {
  console.log(`SKIP: playwright-core not installed (cd ${path.dirname(new URL(import.meta.url).pathname)} && npm ci)`);
  process.exit(SKIP);
}
if (!fs.existsSync(CHROMIUM)) {
  console.log(`SKIP: ${CHROMIUM} missing (apt-get install chromium)`);
  process.exit(SKIP);
}

const children = [];
const tmp = fs.mkdtempSync(path.join(os.tmpdir(), 'alight-gs-browser-'));
let browser = null;

function cleanup() {
  for (const c of children) if (c.exitCode === null) c.kill('SIGTERM');
  fs.rmSync(tmp, { recursive: true, force: true });
}

function fail(msg) {
  console.error(`FAIL: ${msg}`);
  throw new Error(msg);
}

async function waitFor(what, fn, timeoutMs = 10_000) {
  const end = Math.min(Date.now() + timeoutMs, deadline);
  let last;
  while (Date.now() < end) {
    last = await fn();
    if (last) return last;
    await new Promise((r) => setTimeout(r, 100));
  }
  fail(`timed out waiting for ${what}`);
}

function start(bin, argv, name) {
  const child = spawn(bin, argv, { stdio: ['pipe', 'pipe', 'pipe'] });
  children.push(child);
  const lines = [];
  readline.createInterface({ input: child.stdout }).on('line', (l) => lines.push(l));
  readline.createInterface({ input: child.stderr }).on('line', (l) => console.log(`[${name}] ${l}`));
  child.on('exit', (code, sig) => { if (code || sig) console.log(`[${name}] exited ${code ?? sig}`); });
  return { child, lines };
}

async function main() {
  const keyFile = path.join(tmp, 'operator.key');
  fs.writeFileSync(keyFile, Buffer.from(Array.from({ length: 32 }, (_, i) => (i * 37 + 11) & 255)).toString('hex') + '\n', { mode: 0o600 });

  const fixture = start(args.fixture, ['--lcm-url', lcmUrl, '--key-file', keyFile, '--fps', '15'], 'fixture');
  await waitFor('fixture ready', () => fixture.lines.some((l) => l.includes('"ready"')));
  const station = start(args.station, ['--lcm-url', lcmUrl, '--key-file', keyFile, '--port', '0',
    '--sender', 'gs-browser-test'], 'station');
  const url = await waitFor('station URL', () => {
    for (const l of station.lines) {
      const m = /serving (http:\/\/127\.0\.0\.1:\d+\/)/.exec(l);
      if (m) return m[1];
    }
    return null;
  });
  console.log(`station at ${url}`);
  const setPhase = (n) => fixture.child.stdin.write(`phase ${n}\n`);
  const commands = () => fixture.lines.filter((l) => l.includes('"cmd"')).map((l) => JSON.parse(l));

  // A fresh profile folder per run (playwright passes it to chromium as --user-data-dir).
  browser = await chromium.launchPersistentContext(path.join(tmp, 'profile'), {
    executablePath: CHROMIUM,
    headless: true,
    args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
      '--disable-background-networking', '--disable-component-update', '--disable-sync'],
    viewport: { width: 1400, height: 1000 },
  });
  const page = browser.pages()[0] || await browser.newPage();
  const pageErrors = [];
  page.on('pageerror', (e) => pageErrors.push(String(e)));
  page.on('console', (m) => { if (m.type() === 'error') pageErrors.push(m.text()); });
  // A stand-in gamepad behind the Gamepad API (headless Chromium has no real one).
  await page.addInitScript(() => {
    window.__pad = {
      id: 'test pad (standard)', connected: true, mapping: 'standard', axes: [0, 0, 0, 0],
      buttons: Array.from({ length: 17 }, () => ({ pressed: false, value: 0 })),
    };
    navigator.getGamepads = () => [window.__pad];
  });
  const response = await page.goto(url, { timeout: 15_000 });
  // Issue 14: the page may not be framed by another site (clickjacking the command buttons).
  const headers = response.headers();
  if (headers['x-frame-options'] !== 'DENY') fail(`X-Frame-Options ${headers['x-frame-options']}`);
  if (!(headers['content-security-policy'] || '').includes("frame-ancestors 'none'"))
    fail(`Content-Security-Policy ${headers['content-security-policy']}`);

  // 1. The page loads and shows the state.
  await waitFor('phase IDLE on the page', async () => (await page.textContent('#phase')) === 'IDLE');
  console.log('ok: page loaded, phase IDLE');

  // 2. Video frames arrive and change: newer sequence numbers and different pixels.
  const frameSignature = () => page.evaluate(() => {
    const img = document.getElementById('video-camera');
    if (!img.complete || !img.naturalWidth) return null;
    const c = document.createElement('canvas');
    c.width = img.naturalWidth;
    c.height = img.naturalHeight;
    const g = c.getContext('2d');
    g.drawImage(img, 0, 0);
    const d = g.getImageData(0, 0, c.width, c.height).data;
    let h = 0;
    for (let i = 0; i < d.length; i += 4) h = (h * 31 + d[i]) >>> 0;
    return { seq: Number(img.dataset.seq), hash: h, w: c.width, h: c.height };
  });
  const first = await waitFor('a camera frame', frameSignature);
  const second = await waitFor('a newer, different camera frame', async () => {
    const s = await frameSignature();
    return s && s.seq > first.seq + 2 && s.hash !== first.hash ? s : null;
  });
  if (first.w !== 320 || first.h !== 240) fail(`frame size ${first.w}x${first.h}, expected 320x240`);
  await waitFor('a VISION_DIAG frame', () => page.evaluate(() => document.getElementById('video-diag').naturalWidth > 0));
  const fps = await waitFor('a frame rate shown', async () => {
    const f = Number(await page.getAttribute('#stats-camera', 'data-fps'));
    return f > 3 ? f : null;
  });
  console.log(`ok: camera frames #${first.seq} -> #${second.seq} differ, ${fps} fps on the page`);

  // 3. The phase shown follows AUTONOMY_STATUS.
  for (const [n, name] of [[3, 'DETECTION'], [4, 'REFINEMENT'], [5, 'APPROACH']]) {
    setPhase(n);
    await waitFor(`phase ${name}`, async () => (await page.textContent('#phase')) === name, 5000);
  }
  console.log('ok: phase followed DETECTION -> REFINEMENT -> APPROACH');

  // 4. Clicking "go" puts a correctly signed OPERATOR_CMD on LCM.
  await page.selectOption('#mission-select', 'landing');
  await page.click('#btn-go');
  const go = await waitFor('OPERATOR_CMD go at the vehicle', () => commands().find((c) => c.command === 2));
  if (go.verdict !== 'accepted') fail(`go was ${go.verdict}, expected accepted`);
  if (go.mission !== 1) fail(`go mission ${go.mission}, expected 1 (landing)`);
  if (go.sender !== 'gs-browser-test') fail(`sender ${go.sender}`);
  console.log(`ok: click on Go -> signed OPERATOR_CMD accepted by CommandVerifier (seq ${go.seq})`);

  // Keyboard: "a" aborts; arrow up nudges +x.
  await page.keyboard.press('a');
  const abort = await waitFor('abort from the keyboard', () => commands().find((c) => c.command === 3));
  if (abort.verdict !== 'accepted' || abort.seq <= go.seq) fail(`abort ${JSON.stringify(abort)}`);
  await page.keyboard.press('ArrowUp');
  const nudge = await waitFor('nudge from the keyboard', () => commands().find((c) => c.command === 6));
  if (nudge.verdict !== 'accepted' || Math.abs(nudge.nudge[0] - 0.1) > 1e-9) fail(`nudge ${JSON.stringify(nudge)}`);
  // Kill asks first; cancelling sends nothing, confirming sends it.
  await page.click('#btn-kill');
  await waitFor('kill confirmation', () => page.isVisible('#kill-dialog'));
  await page.click('#kill-cancel');
  await new Promise((r) => setTimeout(r, 500));
  if (commands().some((c) => c.command === 5)) fail('kill sent without confirmation');
  await page.click('#btn-kill');
  await page.click('#kill-confirm');
  const kill = await waitFor('confirmed kill', () => commands().find((c) => c.command === 5));
  if (kill.verdict !== 'accepted') fail(`kill ${kill.verdict}`);
  console.log('ok: keyboard abort, nudge, and kill only after confirmation, all accepted');

  // Gamepad: Y takes off; the left stick pushed forward nudges +x.
  const seqBefore = Math.max(...commands().map((c) => c.seq));
  await page.evaluate(() => { window.__pad.buttons[3] = { pressed: true, value: 1 }; });
  const takeoff = await waitFor('takeoff from the gamepad', () => commands().find((c) => c.command === 1));
  await page.evaluate(() => { window.__pad.buttons[3] = { pressed: false, value: 0 }; });
  if (takeoff.verdict !== 'accepted' || takeoff.seq <= seqBefore) fail(`takeoff ${JSON.stringify(takeoff)}`);
  await page.evaluate(() => { window.__pad.axes[1] = -1; });
  const padNudge = await waitFor('nudge from the gamepad stick',
    () => commands().find((c) => c.command === 6 && c.seq > takeoff.seq));
  await page.evaluate(() => { window.__pad.axes[1] = 0; });
  if (padNudge.verdict !== 'accepted' || Math.abs(padNudge.nudge[0] - 0.1) > 1e-9 || padNudge.nudge[1] !== 0)
    fail(`gamepad nudge ${JSON.stringify(padNudge)}`);
  console.log('ok: gamepad Y -> takeoff, left stick forward -> nudge +x, accepted');

  // 5. Acknowledgement (issue 14): the page shows each command acknowledged by the vehicle, the
  // clock offset, and an alarm for a command the vehicle does not acknowledge.
  await waitFor('commands shown as acknowledged', async () =>
    (await page.textContent('#sent')).includes('acknowledged'));
  await waitFor('a clock offset shown', async () =>
    /clock offset [+-]\d/.test(await page.textContent('#clock-offset')));
  // The fixture reads its stdin on a thread of its own: the key is pressed once it said the
  // switch is in force (a loaded machine could otherwise acknowledge the command first).
  const ackSwitched = (on) => fixture.lines.some((l) => l.includes(`"event":"ack","on":${on}`));
  fixture.child.stdin.write('ack off\n');
  await waitFor('the fixture no longer acknowledging', () => ackSwitched(false));
  await page.keyboard.press('a');
  await waitFor('NOT ACKNOWLEDGED alarm', async () =>
    (await page.isVisible('#ack-alarm')) &&
    (await page.textContent('#ack-alarm')).includes('NOT ACKNOWLEDGED'));
  fixture.child.stdin.write('ack on\n');
  await waitFor('the fixture acknowledging again', () => ackSwitched(true));
  console.log('ok: commands acknowledged, clock offset shown, NOT ACKNOWLEDGED alarm when unanswered');

  // 6. Screenshot artifact, after the plots have some history.
  await page.waitForTimeout(1000);
  fs.mkdirSync(outDir, { recursive: true });
  const shot = path.join(outDir, 'ground_station_browser.png');
  await page.screenshot({ path: shot, fullPage: true });
  console.log(`ok: screenshot ${shot}`);

  const rejected = commands().filter((c) => c.verdict !== 'accepted');
  if (rejected.length) fail(`rejected commands: ${JSON.stringify(rejected)}`);
  if (pageErrors.length) fail(`page errors: ${pageErrors.join(' | ')}`);
}

let code = 0;
try {
  await main();
  console.log('PASS');
} catch (e) {
  console.error(e && e.stack ? e.stack : e);
  code = 1;
} finally {
  if (browser) await browser.close().catch(() => {});
  cleanup();
}
process.exit(code);
