// CNCjs's own web page (in the Debian Chromium, driven by playwright-core) running a program on
// `cncore serve --grbl-pty`, as an operator does it: choose cncore's pty in the Connection
// widget, Open, upload a program, press ▶. The page must show Run, then Idle with the work
// position where `cncore run` ends the same program. Screenshots go to --out (docs/senders.md's
// picture is the one taken mid-run).
//   node cncjs_page_test.mjs --cncore BIN --cncjs DIR --playwright DIR --program FILE --out DIR
// Skipped (exit 77, with a message) when CNCjs, playwright-core or Chromium is missing.
import { spawn, execFileSync } from 'node:child_process';
import { createRequire } from 'node:module';
import fs from 'node:fs';
import net from 'node:net';
import os from 'node:os';
import path from 'node:path';
import assert from 'node:assert/strict';

const arg = (name) => {
  const i = process.argv.indexOf('--' + name);
  return i > 0 ? process.argv[i + 1] : undefined;
};
const cncore = path.resolve(arg('cncore'));
const cncjsBin = path.join(path.resolve(arg('cncjs')), 'cncjs', 'bin', 'cncjs');
const program = path.resolve(arg('program'));
const out = path.resolve(arg('out'));
const SKIP = 77;
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
const step = (text) => console.log(`[${new Date().toISOString().slice(11, 19)}] ${text}`);

const chromiumPath = (process.env.PATH || '').split(':').map((d) => path.join(d, 'chromium'))
  .find((p) => fs.existsSync(p));
if (!chromiumPath || !fs.existsSync(cncjsBin)) {
  console.log(`SKIP: needs Chromium on the PATH and CNCjs in ${arg('cncjs')} (the build installs both)`);
  process.exit(SKIP);
}
let chromium;
try {
  chromium = createRequire(path.join(path.resolve(arg('playwright')), 'x.js'))('playwright-core').chromium;
} catch (e) {
  console.log(`SKIP: playwright-core is not installed in ${arg('playwright')}: ${e.message}`);
  process.exit(SKIP);
}

function freePort() {
  return new Promise((resolve) => {
    const s = net.createServer();
    s.listen(0, '127.0.0.1', () => {
      const { port } = s.address();
      s.close(() => resolve(port));
    });
  });
}

// The end point of `cncore run` on the same program (X, Y, Z of the last trajectory row).
function runEnd(work) {
  const csv = path.join(work, 'run.csv');
  execFileSync(cncore, ['run', program, '--trajectory', csv]);
  const rows = fs.readFileSync(csv, 'utf8').trim().split('\n');
  return rows[rows.length - 1].split(',').map(Number).slice(2, 5);
}

async function until(what, cond, seconds) {
  for (let t = 0; t < seconds * 10; ++t) {
    if (await cond()) return;
    await sleep(100);
  }
  throw new Error(`timed out after ${seconds} s waiting for ${what}`);
}

// The Grbl widget's "State" field and the Axes widget's work position, as the operator reads them.
const pageState = (page) => page.evaluate(() => {
  const label = document.querySelector('[title="State"]');
  return label ? label.parentElement.nextElementSibling.innerText.trim() : '';
});
const workPosition = (page) => page.evaluate(() =>
  [...document.querySelectorAll('td[class*="work-position"]')]
    .map((td) => Number(td.firstElementChild.innerText.replace(/\s/g, ''))));

async function operate(page, pty, end) {
  await page.getByText('Choose a port').click();
  await page.getByText(pty, { exact: true }).first().click();
  await page.getByRole('button', { name: 'Open' }).click();
  await until('the page to show Idle', async () => (await pageState(page)) === 'Idle', 30);
  step('CNCjs page: port opened, Grbl state Idle');
  await page.locator('input[type=file]').first().setInputFiles(program);
  await until('the program to load', async () => page.locator('button:has(i.fa-play)').isEnabled(), 20);
  await page.locator('button:has(i.fa-play)').click();
  await until('the page to show Run', async () => (await pageState(page)) === 'Run', 120);
  await sleep(1500);  // the path half drawn, the tool on it
  await page.screenshot({ path: path.join(out, 'cncjs-running.png') });
  step('CNCjs page: Run (screenshot cncjs-running.png)');
  let idle = 0;  // Idle held for 2 s: not a status report from between two lines
  await until('the page to show Idle at the end', async () => {
    idle = (await pageState(page)) === 'Idle' ? idle + 1 : 0;
    return idle >= 20;
  }, 300);
  const wpos = await workPosition(page);
  await page.screenshot({ path: path.join(out, 'cncjs-done.png') });
  step(`CNCjs page: Idle, work position ${wpos} (cncore run ends at ${end})`);
  assert.equal(wpos.length, 3, 'the Axes widget shows X, Y and Z');
  wpos.forEach((v, i) => assert.ok(Math.abs(v - end[i]) < 1e-3,
                                   `axis ${i}: the page shows ${v}, cncore run ends at ${end[i]}`));
}

async function main() {
  fs.rmSync(out, { recursive: true, force: true });
  fs.mkdirSync(out, { recursive: true });
  const work = fs.mkdtempSync(path.join(os.tmpdir(), 'cncore-cncjs-page-'));
  const pty = path.join(work, 'ttyCNCORE');
  const end = runEnd(work);
  const serve = spawn(cncore, ['serve', '--no-realtime', '--state-dir', path.join(work, 'state'),
    '--grbl-pty', pty], { stdio: ['pipe', 'ignore', 'inherit'] });
  // CNCjs lists the serial ports udev knows, plus the `ports` of its configuration: the pty.
  const config = path.join(work, 'cncrc.json');
  fs.writeFileSync(config, JSON.stringify({
    secret: 'cncore-cncjs-page-test', state: { checkForUpdates: false },
    ports: [{ path: pty, manufacturer: 'cncore serve --grbl-pty' }] }));
  const port = await freePort();
  const cncjs = spawn(process.execPath, [cncjsBin, '--host', '127.0.0.1', '--port', String(port),
    '--config', config], { stdio: 'ignore', env: { ...process.env, HOME: work } });
  const browser = await chromium.launch({ executablePath: chromiumPath,
    args: ['--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--no-sandbox'] });
  try {
    const page = await browser.newPage({ viewport: { width: 1400, height: 900 } });
    // CNCjs draws the loaded program in WebGL on the CPU (SwiftShader): on a loaded two-core
    // machine its page can be busy for tens of seconds, and a click waits for it.
    page.setDefaultTimeout(120000);
    const errors = [];
    page.on('pageerror', (e) => errors.push(e.message));
    await until('CNCjs to answer', async () => {
      try {
        return (await page.goto(`http://127.0.0.1:${port}/`)).ok();
      } catch {
        return false;
      }
    }, 60);
    await operate(page, pty, end);
    assert.deepEqual(errors, [], 'no script errors on CNCjs page');
  } finally {
    await browser.close();
    cncjs.kill();
    serve.kill('SIGTERM');
  }
  console.log('cncjs page test: passed');
}

main().catch((e) => {
  console.log(`FAIL ${e.stack}`);
  process.exit(1);
});
