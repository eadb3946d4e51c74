#!/usr/bin/env node
// CNCjs (pinned in package.json) driving `cncore serve --grbl-pty` as a Grbl port, through
// CNCjs's own client API (socket.io, as its web page does). Outcomes from cncore's served
// trajectory (--trajectory) and from the state CNCjs reports.
//   node cncjs_test.js CNCORE MODULES_DIR [SHARED_DIR]
// Skipped (exit 77, with a message) when CNCjs is not installed in MODULES_DIR.
'use strict';
const fs = require('fs');
const os = require('os');
const path = require('path');
const net = require('net');
const { spawn, execFileSync } = require('child_process');

const [cncoreArg, modulesArg, shared] = process.argv.slice(2);
const cncore = cncoreArg && path.resolve(cncoreArg);
const modules = modulesArg && path.resolve(modulesArg);
const cncjsBin = path.join(modules || '', 'cncjs', 'bin', 'cncjs');
if (!cncore || !modules || !fs.existsSync(cncjsBin)) {
  console.log(`skipped: CNCjs is not installed in ${modules} ` +
              '(cmake --build --preset release --target cncjs-install)');
  process.exit(77);
}
const io = require(path.join(modules, 'socket.io-client'));
const jwt = require(path.join(modules, 'jsonwebtoken'));

const fails = [];
// Under the sanitizers cncore runs several times slower, so times are reported, not bounded.
const sanitized = Boolean(process.env.CNCORE_SANITIZED);
function timing(cond, what) {
  if (sanitized) console.log(`note ${what} (sanitizer build: not bounded)`);
  else check(cond, what);
}
function check(cond, what) {
  console.log((cond ? 'ok   ' : 'FAIL ') + what);
  if (!cond) fails.push(what);
}
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

function freePort() {
  return new Promise((resolve) => {
    const s = net.createServer();
    s.listen(0, '127.0.0.1', () => {
      const { port } = s.address();
      s.close(() => resolve(port));
    });
  });
}

function readTrajectory(file) {
  const rows = fs.readFileSync(file, 'utf8').trim().split('\n').slice(1);
  return rows.map((r) => r.split(',').map(Number)).map((c) => [c[0], c[2], c[3], c[4]]);
}
// Seconds from the first cycle that moves to the last one.
function motionTime(rows) {
  let first = -1;
  let last = -1;
  for (let i = 1; i < rows.length; ++i) {
    if (rows[i][1] !== rows[i - 1][1] || rows[i][2] !== rows[i - 1][2] ||
        rows[i][3] !== rows[i - 1][3]) {
      if (first < 0) first = i - 1;
      last = i;
    }
  }
  return first < 0 ? 0 : rows[last][0] - rows[first][0];
}
function maxSpeed(rows, from) {  // from: the first row
  let v = 0;
  for (let i = from + 1; i < rows.length; ++i) {
    const dt = rows[i][0] - rows[i - 1][0];
    const d = Math.hypot(rows[i][1] - rows[i - 1][1], rows[i][2] - rows[i - 1][2],
                         rows[i][3] - rows[i - 1][3]);
    if (dt > 0) v = Math.max(v, (d / dt) * 60);
  }
  return v;
}
function circle(chords) {
  const lines = ['G21 G90 G17', 'G0 X50 Y0', 'G1 F3000'];
  for (let i = 1; i <= chords; ++i) {
    const a = (2 * Math.PI * i) / chords;
    lines.push(`X${(50 * Math.cos(a)).toFixed(4)} Y${(50 * Math.sin(a)).toFixed(4)}`);
  }
  return lines.concat(['M2']).join('\n') + '\n';
}

async function main() {
  const work = fs.mkdtempSync(path.join(os.tmpdir(), 'cncore-cncjs-'));
  const pty = path.join(work, 'ttyCNCORE');
  const traj = path.join(work, 'served.csv');
  const serve = spawn(cncore, ['serve', '--no-realtime', '--state-dir', path.join(work, 'state'),
    '--grbl-pty', pty, '--trajectory', traj], { stdio: ['pipe', 'ignore', 'inherit'] });
  const secret = 'cncore-cncjs-test';
  const config = path.join(work, 'cncrc.json');
  fs.writeFileSync(config, JSON.stringify({ secret, state: { checkForUpdates: false } }));
  const port = await freePort();
  const cncjs = spawn(process.execPath, [cncjsBin, '--host', '127.0.0.1', '--port', String(port),
    '--config', config], { stdio: 'ignore', env: { ...process.env, HOME: work } });
  // The trajectory file is complete once serve has ended (it is written whole, then renamed).
  const served = new Promise((resolve) => serve.on('exit', resolve));
  let phases = null;
  try {
    phases = await run(work, pty, port, secret);
  } finally {
    cncjs.kill();
    serve.kill('SIGTERM');
    await served;
  }
  if (phases) analyse(work, traj, phases);
  console.log(`${fails.length} failed`);
  process.exit(fails.length ? 1 : 0);
}

async function run(work, pty, port, secret) {
  const token = jwt.sign({ id: '', name: '' }, secret, { expiresIn: '1h' });
  let socket = null;
  for (let i = 0; i < 120 && !socket; ++i) {
    await sleep(500);
    socket = await new Promise((resolve) => {
      const s = io.connect(`http://127.0.0.1:${port}`, { query: `token=${token}`, reconnection: false });
      s.on('connect', () => resolve(s));
      s.on('connect_error', () => { s.close(); resolve(null); });
      s.on('error', () => { s.close(); resolve(null); });
    });
  }
  check(socket !== null, 'CNCjs started headless and its socket.io API answers');
  if (!socket) return null;
  let ctl = {};
  let workflow = '';
  let sender = {};
  socket.on('controller:state', (type, state) => { ctl = state; });
  socket.on('workflow:state', (s) => { workflow = s; });
  socket.on('sender:status', (s) => { sender = s; });
  const seen = [];
  socket.on('controller:state', (type, state) => {
    const a = state && state.status && state.status.activeState;
    if (a && seen[seen.length - 1] !== a) seen.push(a);
  });
  const openErr = await new Promise((resolve) => {
    socket.emit('open', pty, { controllerType: 'Grbl', baudrate: 115200 }, resolve);
  });
  check(!openErr, `CNCjs opened cncore's pty as a Grbl port (${openErr || 'no error'})`);
  const until = async (cond, seconds) => {
    for (let t = 0; t < seconds * 20; ++t) {
      if (cond()) return true;
      await sleep(50);
    }
    return false;
  };
  check(await until(() => ctl.status && ctl.status.activeState === 'Idle', 20),
        `CNCjs sees cncore Idle (${JSON.stringify(ctl.status)})`);
  const cmd = (...args) => socket.emit('command', pty, ...args);
  // Programs are 4 s apart: in the served trajectory the three longest pauses part them.
  const runProgram = async (name, text, during) => {
    await sleep(4000);
    await new Promise((resolve) => cmd('gcode:load', name, text, {}, resolve));
    cmd('gcode:start');
    await until(() => workflow === 'running', 10);
    if (during) await during();
    const done = await until(() => workflow === 'idle' && sender.total > 0 &&
                             sender.received === sender.total &&
                             ctl.status.activeState === 'Idle', 300);
    if (!done) {
      console.log(`${name}: workflow ${workflow}, sender ${JSON.stringify(sender)}, ` +
                  `state ${JSON.stringify(ctl.status)}`);
    }
    // CNCjs's state comes from its `?` polls (4 Hz): Idle must hold for a second, so that a
    // report from before the last lines ran is not taken for the end.
    const sendSeconds = (sender.elapsedTime || 0) / 1000;
    for (let still = 0; still < 20;) {
      await sleep(50);
      still = ctl.status.activeState === 'Idle' ? still + 1 : 0;
    }
    return { done, sendSeconds };
  };

  // A corpus program (UGS's streaming stress test: 12 002 short lines; no M6, on which CNCjs
  // would pause for the operator), then the final work position against cncore's.
  const corpus = shared && path.join(shared, 'testdata', 'gcode', 'ugs', 'stress_test.gcode');
  const program = corpus && fs.existsSync(corpus) ? corpus
    : path.join(__dirname, '..', '..', '..', 'examples', 'pocket-with-arcs.ngc');
  const r1 = await runProgram(path.basename(program), fs.readFileSync(program, 'utf8'));
  check(r1.done, `${path.basename(program)} ran to its end through CNCjs (${JSON.stringify(sender)})`);
  const phases = { program, wpos: ctl.status.wpos, seen: seen.slice(), done: [r1.done],
                   sendSeconds: r1.sendSeconds };
  seen.length = 0;
  // Hold and resume from CNCjs: the tool stands still in between.
  const r2 = await runProgram('circle1000.ngc', circle(1000), async () => {
    await sleep(2000);
    cmd('feedhold');
    await until(() => ctl.status.activeState === 'Hold', 5);
    await sleep(1000);
    cmd('cyclestart');
  });
  phases.holdSeen = seen.slice();
  // Feed override +10 % from CNCjs mid-program.
  const r3 = await runProgram('circle1000.ngc', circle(1000), async () => {
    await sleep(1500);
    cmd('feedOverride', 10);
  });
  // The 36 000-chord circle streamed through CNCjs.
  const r4 = await runProgram('circle36000.ngc', circle(36000));
  Object.assign(phases, { hold: r2, override: r3, big: r4 });
  phases.done.push(r2.done, r3.done, r4.done);
  socket.close();
  return phases;
}

// The trajectory cut into `n` programs at its n − 1 longest pauses (the tool standing still).
function split(rows, n) {
  const gaps = [];
  let last = -1;
  for (let i = 1; i < rows.length; ++i) {
    if (rows[i][1] === rows[i - 1][1] && rows[i][2] === rows[i - 1][2] &&
        rows[i][3] === rows[i - 1][3]) continue;
    if (last >= 0) gaps.push({ at: last, len: rows[i - 1][0] - rows[last][0] });
    last = i;
  }
  const cuts = gaps.sort((a, b) => b.len - a.len).slice(0, n - 1).map((g) => g.at + 1)
    .sort((a, b) => a - b);
  const parts = [];
  let from = 0;
  for (const c of cuts.concat([rows.length])) {
    parts.push(rows.slice(from, c));
    from = c;
  }
  return parts;
}

function runTime(work, name, text) {
  const file = path.join(work, name);
  fs.writeFileSync(file, text);
  execFileSync(cncore, ['run', file, '--trajectory', `${file}.csv`]);
  return readTrajectory(`${file}.csv`);
}

function analyse(work, traj, p) {
  const [first, hold, ov, big] = split(readTrajectory(traj), 4);
  check(p.done.every((d) => d), `every program ran to its end through CNCjs (${p.done})`);
  const end = first[first.length - 1].slice(1);
  check(['x', 'y', 'z'].every((a, i) => Math.abs(Number(p.wpos[a]) - end[i]) < 1e-3),
        `${path.basename(p.program)}: CNCjs's work position ${JSON.stringify(p.wpos)} is ` +
        `cncore's final set-point ${end}`);
  const ref = runTime(work, 'corpus.ngc', fs.readFileSync(p.program, 'utf8'));
  const refEnd = ref[ref.length - 1].slice(1);
  check(end.every((v, i) => Math.abs(v - refEnd[i]) < 1e-6), `…and where \`cncore run\` ends (${refEnd})`);
  // The tool may stop only where CNCjs had not sent the lines yet: no slower than run or than
  // CNCjs's own sending, whichever is longer.
  const t1 = motionTime(first);
  const t1run = motionTime(ref);
  timing(t1 <= Math.max(1.05 * t1run, p.sendSeconds + 0.5),
        `…in ${t1.toFixed(3)} s against ${t1run.toFixed(3)} s in run; CNCjs took ` +
        `${p.sendSeconds.toFixed(3)} s to send its lines`);
  check(p.seen.includes('Run') && p.seen[p.seen.length - 1] === 'Idle', `states CNCjs saw: ${p.seen}`);
  const tRun = motionTime(runTime(work, 'c1000.ngc', circle(1000)));
  const t2 = motionTime(hold);
  check(p.holdSeen.includes('Hold'), `feed hold / cycle start from CNCjs: ${p.holdSeen}`);
  check(t2 > tRun + 0.5, `the hold stopped the tool in cncore's trajectory (${t2.toFixed(2)} s ` +
        `against ${tRun.toFixed(2)} s without)`);
  const v = maxSpeed(ov, 0);
  check(v > 3000 * 1.07 && v < 3000 * 1.1 * 1.01,
        `feed override +10 % from CNCjs: ${v.toFixed(0)} mm/min on the F3000 circle`);
  const t36run = motionTime(runTime(work, 'c36000.ngc', circle(36000)));
  const t36 = motionTime(big);
  timing(t36 <= Math.max(1.05 * t36run, p.big.sendSeconds + 0.5),
        `36 000-chord circle through CNCjs: ${t36.toFixed(3)} s against ${t36run.toFixed(3)} s in ` +
        `run (${(t36 / t36run).toFixed(3)}x); CNCjs took ${p.big.sendSeconds.toFixed(3)} s to ` +
        `send its lines (the target 1.05x holds when CNCjs sends faster than the tool runs)`);
}

main().catch((e) => {
  console.log(`FAIL ${e.stack}`);
  process.exit(1);
});
