// rvc dashboard in a real browser: Debian's Chromium driven by playwright-core.
// It asserts what a user sees: the runs, each property's verdict, the
// violations and their witness lines, the filter, and rows written to the
// database after the page loaded showing up without a reload.
//
// The database is written with Python's sqlite3 (Node 20 has no SQLite) using
// the DDL of src/store/schema.cpp, as the monitor would write it. With
// RVC_SCREENSHOTS=1 the test also renders docs/img/dashboard*.png (CI does not,
// so it never rewrites the docs). Chromium talks to 127.0.0.1 only: names
// resolve nowhere else, no proxy, and every other request is aborted and
// counted (the page must load nothing from elsewhere).
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { spawn, execFileSync } from 'node:child_process';
import { mkdtempSync, mkdirSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { chromium } from 'playwright-core';

const here = path.dirname(fileURLToPath(import.meta.url));
const root = path.resolve(here, '..', '..');
const RVC = path.resolve(process.env.RVC_BIN || path.join(root, 'build', 'release', 'rvc'));
const SCREENSHOTS = process.env.RVC_SCREENSHOTS === '1';

// --- the database ------------------------------------------------------------
const SCHEMA = [  // src/store/schema.cpp, Dialect::Sqlite
  'CREATE TABLE IF NOT EXISTS runs (run TEXT PRIMARY KEY, command TEXT, inputs TEXT, time_model TEXT, started_at DOUBLE PRECISION, ended_at DOUBLE PRECISION, exit_status INTEGER, end_reason TEXT, counters TEXT)',
  'CREATE TABLE IF NOT EXISTS properties (run TEXT NOT NULL, name TEXT NOT NULL, spec TEXT, PRIMARY KEY (run, name))',
  'CREATE TABLE IF NOT EXISTS verdicts (id INTEGER PRIMARY KEY AUTOINCREMENT, run TEXT NOT NULL, property TEXT NOT NULL, time DOUBLE PRECISION, value INTEGER, wall DOUBLE PRECISION)',
  'CREATE INDEX IF NOT EXISTS verdicts_by_run ON verdicts (run, property, id)',
  'CREATE TABLE IF NOT EXISTS violations (id INTEGER PRIMARY KEY AUTOINCREMENT, run TEXT NOT NULL, property TEXT NOT NULL, time DOUBLE PRECISION, wall DOUBLE PRECISION, witness TEXT)',
  'CREATE INDEX IF NOT EXISTS violations_by_run ON violations (run, id)',
  'CREATE TABLE IF NOT EXISTS counters (id INTEGER PRIMARY KEY AUTOINCREMENT, run TEXT NOT NULL, wall DOUBLE PRECISION, counters TEXT)',
  'CREATE INDEX IF NOT EXISTS counters_by_run ON counters (run, id)',
];
// Statements with parameters, run in one transaction by python3's sqlite3.
const PY = `import json, sqlite3, sys
db = sqlite3.connect(sys.argv[1])
db.execute("PRAGMA journal_mode=WAL")
with db:
    for sql, params in json.load(sys.stdin):
        db.execute(sql, params)
db.close()`;
function sql(db, statements) {
  execFileSync('python3', ['-c', PY, db], { input: JSON.stringify(statements.map((s) => (Array.isArray(s) ? s : [s, []]))) });
}

const now = Date.now() / 1000;
const SPECS = {
  hazard_on_emergency: 'historically({emergency} -> once[0:1]{hazard_lights})',
  speed_limit: '{velocity_kmh <= limit_kmh + 2}',
  gear_park_before_off: 'historically({engine_off} -> {gear == "park"})',
  steer_rate_limit: '{abs(steer_rate) < 0.6}',
};
const LIVE = '20261123-101500-4242-a3f9';
const HAZARD_LATE = '20261123-091200-4107-77c1';
const DRIVE = '20261123-081000-3988-0b2e';

// The messages up to a violation, as the store keeps them (one JSON line each).
function witness(input, seq0, t0, rows) {
  return JSON.stringify(rows.map((r, i) => ({ input, seq: seq0 + i, payload: JSON.stringify({ stamp: +(t0 + i * 0.1).toFixed(1), ...r }) })));
}
const verdict = (run, property, time, value, wall) => ['INSERT INTO verdicts (run, property, time, value, wall) VALUES (?,?,?,?,?)', [run, property, time, value ? 1 : 0, wall]];
const violation = (run, property, time, wall, w) => ['INSERT INTO violations (run, property, time, wall, witness) VALUES (?,?,?,?,?)', [run, property, time, wall, w]];
const snapshot = (run, wall, c) => ['INSERT INTO counters (run, wall, counters) VALUES (?,?,?)', [run, wall, JSON.stringify(c)]];

function buildDatabase(db) {
  const s = [...SCHEMA];
  const run = (id, command, inputs, model, started, ended, exit, reason, counters = null) =>
    s.push(['INSERT INTO runs VALUES (?,?,?,?,?,?,?,?,?)', [id, command, JSON.stringify(inputs), model, started, ended, exit, reason,
                                                          counters && JSON.stringify(counters)]]);
  const props = (id, names) => names.forEach((n) => s.push(['INSERT INTO properties VALUES (?,?,?)', [id, n, SPECS[n]]]));

  // An earlier drive: everything held.
  run(DRIVE, 'rvc check -p autoware.yaml --output sqlite:results.db drive.jsonl', ['drive.jsonl'], 'discrete', now - 7200, now - 7190, 0, 'end of input');
  props(DRIVE, ['hazard_on_emergency', 'speed_limit', 'gear_park_before_off']);
  for (const p of ['hazard_on_emergency', 'speed_limit', 'gear_park_before_off']) s.push(verdict(DRIVE, p, 0, true, now - 7199));

  // A scenario where the hazard lights come on too late.
  run(HAZARD_LATE, 'rvc check -p autoware.yaml --output sqlite:results.db fault-hazard-late.jsonl', ['fault-hazard-late.jsonl'], 'discrete', now - 3600, now - 3590, 1, 'end of input',
      { input: 'fault-hazard-late.jsonl', received: 200000, checked: 200000, rejected: 0, dropped: {}, verdicts: 4, violations: 1 });
  props(HAZARD_LATE, ['hazard_on_emergency', 'speed_limit', 'gear_park_before_off']);
  s.push(verdict(HAZARD_LATE, 'hazard_on_emergency', 0, true, now - 3599), verdict(HAZARD_LATE, 'speed_limit', 0, true, now - 3599),
         verdict(HAZARD_LATE, 'gear_park_before_off', 0, true, now - 3599), verdict(HAZARD_LATE, 'hazard_on_emergency', 42, false, now - 3595));
  s.push(violation(HAZARD_LATE, 'hazard_on_emergency', 42, now - 3595, witness('fault-hazard-late.jsonl', 38, 3.8,
    [{ emergency: false, hazard_lights: false }, { emergency: true, hazard_lights: false }, { emergency: true, hazard_lights: false },
     { emergency: true, hazard_lights: false }, { emergency: true, hazard_lights: false }])));

  // The live run: a monitor on Zenoh, dense time (seconds).
  run(LIVE, 'rvc monitor --input zenoh:vehicle/status --input zenoh:vehicle/control -p autoware.yaml --dense --output sqlite:results.db',
      ['zenoh:vehicle/status', 'zenoh:vehicle/control'], 'dense', now - 45, null, null, null);
  props(LIVE, Object.keys(SPECS));
  for (const p of Object.keys(SPECS)) s.push(verdict(LIVE, p, 0, true, now - 44));
  const status = (v, limit) => ({ velocity_kmh: v, limit_kmh: limit, gear: 'drive', hazard_lights: false, emergency: false });
  s.push(verdict(LIVE, 'speed_limit', 12.4, false, now - 32), verdict(LIVE, 'speed_limit', 14.1, true, now - 30));
  s.push(violation(LIVE, 'speed_limit', 12.4, now - 32, witness('zenoh:vehicle/status', 118, 12.0,
    [status(49.1, 50), status(50.6, 50), status(51.4, 50), status(52.2, 50), status(52.9, 50)])));
  s.push(verdict(LIVE, 'steer_rate_limit', 20.7, false, now - 24), verdict(LIVE, 'steer_rate_limit', 21.0, true, now - 24));
  s.push(violation(LIVE, 'steer_rate_limit', 20.7, now - 24, witness('zenoh:vehicle/control', 407, 20.3,
    [{ steer: 0.12, steer_rate: 0.21 }, { steer: 0.15, steer_rate: 0.34 }, { steer: 0.21, steer_rate: 0.58 }, { steer: 0.29, steer_rate: 0.71 }])));
  s.push(verdict(LIVE, 'speed_limit', 31.0, false, now - 14));
  s.push(violation(LIVE, 'speed_limit', 31.0, now - 14, witness('zenoh:vehicle/status', 306, 30.6,
    [status(47.9, 50), status(50.2, 50), status(51.8, 50), status(53.0, 50)])));
  s.push(verdict(LIVE, 'speed_limit', 33.2, true, now - 12));
  // Counter snapshots, one a second per input.
  for (let k = 0; k <= 20; k++) {
    const wall = now - 20 + k;
    s.push(snapshot(LIVE, wall, { input: 'zenoh:vehicle/status', received: 1000 + 100 * k, checked: 1000 + 100 * k, rejected: 0, gaps: k > 12 ? 2 : 0, duplicates: 0, publishers: 1, publisher_restarts: 0 }));
    s.push(snapshot(LIVE, wall + 0.5, { input: 'zenoh:vehicle/control', received: 2000 + 200 * k, checked: 2000 + 200 * k, rejected: k > 15 ? 1 : 0, gaps: 0, duplicates: 0, publishers: 1, publisher_restarts: 0 }));
  }
  sql(db, s);
}

// --- the server and the browser ----------------------------------------------
let dir, db, server, port, browser, context, page;
const foreign = [];  // requests to anything but the dashboard

// `rvc dashboard` on port 0; resolves to [process, port] once it says where it serves.
function startDashboard(dbPath) {
  // From the database's directory, so the page shows sqlite:results.db as a user would type it.
  // --silent-after 45: the live run's last counters were written when the database was built; a
  // browser that took over 10 s to start on a loaded machine saw it as silent (CI, 2026-11-28). The
  // dead run below is 60 s old.
  const proc = spawn(RVC, ['dashboard', '--db', `sqlite:${path.basename(dbPath)}`, '--listen', '127.0.0.1:0', '--poll', '0.1',
                           '--silent-after', '45'],
                     { cwd: path.dirname(dbPath), stdio: ['ignore', 'ignore', 'pipe'] });
  return new Promise((resolve, reject) => {
    let err = '';
    const timer = setTimeout(() => reject(new Error('rvc dashboard did not start: ' + err)), 15000);
    proc.stderr.on('data', (d) => {
      err += d;
      const m = err.match(/serving \S+ on http:\/\/127\.0\.0\.1:(\d+)/);
      if (m) { clearTimeout(timer); resolve([proc, Number(m[1])]); }
    });
    proc.on('exit', (code) => reject(new Error(`rvc dashboard exited (${code}): ${err}`)));
  });
}
// SIGTERM with an event stream open must still be a clean stop (exit 0).
async function stopDashboard(proc) {
  if (proc.exitCode !== null) return proc.exitCode;
  const exited = new Promise((resolve) => proc.on('exit', resolve));
  proc.kill('SIGTERM');
  return exited;
}

before(async () => {
  dir = mkdtempSync(path.join(tmpdir(), 'rvc-dashboard-'));
  db = path.join(dir, 'results.db');
  buildDatabase(db);
  [server, port] = await startDashboard(db);
  browser = await chromium.launch({
    executablePath: '/usr/bin/chromium',
    args: ['--no-sandbox', '--no-proxy-server', '--host-resolver-rules=MAP * ~NOTFOUND, EXCLUDE 127.0.0.1',
           '--disable-background-networking', '--disable-component-update', '--disable-sync', '--no-first-run'],
  });
  context = await browser.newContext({ viewport: { width: 1280, height: 800 } });
  await context.route('**/*', (route) => {
    const url = new URL(route.request().url());
    if (url.hostname === '127.0.0.1' && /^\d+$/.test(url.port)) return route.continue();  // the dashboards
    foreign.push(url.href);
    return route.abort();
  });
  page = await context.newPage();
  await page.goto(`http://127.0.0.1:${port}/`);
  await page.waitForSelector(`#run[data-run="${LIVE}"]`);  // the newest run, loaded
  await page.waitForSelector('#status[data-state="live"]');
});

after(async () => {
  const code = server ? await stopDashboard(server) : 0;  // before the browser: its stream is still open
  if (browser) await browser.close();
  if (dir) rmSync(dir, { recursive: true, force: true });
  assert.equal(code, 0);
});

const row = (name) => page.locator(`#properties [data-property="${name}"]`);

test('the run list shows every run, newest first, the live one marked', async () => {
  const runs = page.locator('#runs li[data-run]');
  assert.deepEqual(await runs.evaluateAll((lis) => lis.map((li) => li.dataset.run)), [LIVE, HAZARD_LATE, DRIVE]);
  assert.match(await runs.nth(0).innerText(), /live/);
  assert.doesNotMatch(await runs.nth(1).innerText(), /live/);
  assert.match(await runs.nth(1).innerText(), /1 violation/);
  assert.match(await runs.nth(0).getAttribute('class'), /selected/);  // the newest is shown first
});

test('each property shows its current verdict and a timeline', async () => {
  for (const name of Object.keys(SPECS)) assert.equal(await row(name).getAttribute('data-value'), 'true', name);
  assert.equal(await row('speed_limit').locator('.verdict').innerText(), 'true');
  assert.match(await row('speed_limit').innerText(), /2 violations/);
  assert.equal(await row('speed_limit').locator('svg.timeline .seg-false').count(), 2);  // red where false
  assert.equal(await row('hazard_on_emergency').locator('svg.timeline .seg-false').count(), 0);
  assert.match(await page.locator('#counters').innerText(), /zenoh:vehicle\/status/);
  assert.equal(await page.locator('#counters tr[data-input="zenoh:vehicle/status"] [data-counter="received"]').innerText(), '3,000');
  assert.equal(await page.locator('#counters tr[data-input="zenoh:vehicle/status"] [data-counter="lost"]').innerText(), '2');
  assert.equal(await page.locator('#counters tr[data-input="zenoh:vehicle/status"] [data-counter="rate"]').innerText(), '100');
});

test('the violation list, newest first; a click shows the witness', async () => {
  const items = page.locator('#violations li[data-violation-id]');
  assert.equal(await items.count(), 3);
  assert.deepEqual(await items.evaluateAll((lis) => lis.map((li) => li.dataset.violationProperty)), ['speed_limit', 'steer_rate_limit', 'speed_limit']);
  const first = items.nth(0);
  assert.match(await first.innerText(), /t=31 s/);
  assert.equal(await first.locator('.witness').isVisible(), false);
  await first.locator('.violation-head').click();
  const lines = first.locator('.witness-line');
  await lines.first().waitFor();
  assert.equal(await lines.count(), 4);
  assert.match(await lines.nth(3).innerText(), /"velocity_kmh":53/);  // the violating message, last
  assert.match(await lines.nth(3).innerText(), /zenoh:vehicle\/status/);
  if (SCREENSHOTS) {
    mkdirSync(path.join(root, 'docs', 'img'), { recursive: true });
    await page.screenshot({ path: path.join(root, 'docs', 'img', 'dashboard-witness.png') });
  }
  await first.locator('.violation-head').click();
  assert.equal(await first.locator('.witness').isVisible(), false);
});

test('the filter hides properties and violations that do not match', async () => {
  await page.fill('#filter', 'speed');
  assert.equal(await row('speed_limit').isVisible(), true);
  assert.equal(await row('hazard_on_emergency').isVisible(), false);
  assert.equal(await row('steer_rate_limit').isVisible(), false);
  assert.equal(await page.locator('#violations li[data-violation-id]:visible').count(), 2);
  await page.fill('#filter', '');
  assert.equal(await row('hazard_on_emergency').isVisible(), true);
  assert.equal(await page.locator('#violations li[data-violation-id]:visible').count(), 3);
});

test('rows written after the page loaded appear without a reload', async () => {
  await page.evaluate(() => { window.__sameDocument = true; });
  const t = 43.5, wall = Date.now() / 1000;
  sql(db, [
    verdict(LIVE, 'hazard_on_emergency', t, false, wall),
    violation(LIVE, 'hazard_on_emergency', t, wall, witness('zenoh:vehicle/status', 431, 42.9,
      [{ emergency: false, hazard_lights: false }, { emergency: true, hazard_lights: false }, { emergency: true, hazard_lights: false }])),
    snapshot(LIVE, wall, { input: 'zenoh:vehicle/status', received: 3150, checked: 3150, rejected: 0, gaps: 2, duplicates: 0, publishers: 1, publisher_restarts: 1 }),
    snapshot(LIVE, wall + 0.2, { input: 'zenoh:vehicle/control', received: 6100, checked: 6100, rejected: 1, gaps: 0, duplicates: 0, publishers: 1, publisher_restarts: 0 }),
  ]);
  await page.waitForSelector('#properties [data-property="hazard_on_emergency"][data-value="false"]', { timeout: 5000 });
  await page.waitForSelector('#violations li[data-violation-property="hazard_on_emergency"]', { timeout: 5000 });
  assert.equal(await page.evaluate(() => window.__sameDocument), true);  // no reload
  assert.equal(await row('hazard_on_emergency').locator('.verdict').innerText(), 'false');
  assert.equal(await page.locator('#violations li[data-violation-id]').first().getAttribute('data-violation-property'), 'hazard_on_emergency');
  await page.waitForFunction(() => document.querySelector('#counters tr[data-input="zenoh:vehicle/status"] [data-counter="publisher_restarts"]').textContent === '1');
  assert.match(await page.locator('#runs li[data-run]').nth(0).innerText(), /4 violations/);
  if (SCREENSHOTS) await page.screenshot({ path: path.join(root, 'docs', 'img', 'dashboard.png') });
});

test('a run that ends is shown as ended, live', async () => {
  sql(db, [['UPDATE runs SET ended_at = ?, exit_status = 1, end_reason = ? WHERE run = ?', [Date.now() / 1000, 'signal', LIVE]]]);
  await page.waitForSelector(`#runs li[data-run="${LIVE}"][data-live="false"]`, { timeout: 5000 });
  assert.match(await page.locator('#run-info').innerText(), /exit 1 \(signal\)/);
});

test('choosing another run shows its properties and violations', async () => {
  await page.locator(`#runs li[data-run="${HAZARD_LATE}"]`).click();
  await page.waitForSelector(`#run[data-run="${HAZARD_LATE}"]`);
  assert.equal(await row('hazard_on_emergency').getAttribute('data-value'), 'false');
  assert.equal(await page.locator('#properties [data-property="steer_rate_limit"]').count(), 0);
  assert.equal(await page.locator('#violations li[data-violation-id]').count(), 1);
  await page.locator('#violations li[data-violation-id] .violation-head').click();
  assert.equal(await page.locator('#violations .witness-line').count(), 5);
  assert.match(await page.locator('#run-info').innerText(), /fault-hazard-late\.jsonl/);
  // The timeline reaches the last checked step (200,000 steps: 199999), not the last change (42).
  assert.match(await page.locator('#axis .axis-range').innerText(), /step 0[\s\S]*step 199999/);
  assert.match(page.url(), new RegExp(`#run=${HAZARD_LATE}$`));
});

test('an empty database: the first run appears and opens by itself', async () => {
  const empty = path.join(dir, 'empty.db');
  sql(empty, SCHEMA);
  const [proc, emptyPort] = await startDashboard(empty);
  const p2 = await context.newPage();
  try {
    await p2.goto(`http://127.0.0.1:${emptyPort}/`);
    await p2.waitForSelector('#status[data-state="live"]');
    assert.match(await p2.locator('#runs').innerText(), /No runs yet/);
    sql(empty, [['INSERT INTO runs (run, command, inputs, time_model, started_at) VALUES (?,?,?,?,?)', ['r-first', 'rvc monitor', '[]', 'discrete', Date.now() / 1000]],
                ['INSERT INTO properties VALUES (?,?,?)', ['r-first', 'speed_limit', SPECS.speed_limit]],
                verdict('r-first', 'speed_limit', 0, true, Date.now() / 1000)]);
    await p2.waitForSelector('#run[data-run="r-first"]', { timeout: 5000 });
    assert.equal(await p2.locator('#properties [data-property="speed_limit"]').getAttribute('data-value'), 'true');
  } finally {
    await p2.close();
    assert.equal(await stopDashboard(proc), 0);
  }
});

test('a run whose monitor died without an end is marked silent', async () => {
  // Started a minute ago, no end and no counters since: rvc dashboard says "silent" (--silent-after 45).
  sql(db, [['INSERT INTO runs (run, command, inputs, time_model, started_at) VALUES (?,?,?,?,?)',
            ['r-dead', 'rvc monitor', '[]', 'discrete', Date.now() / 1000 - 60]]]);
  const marker = page.locator('#runs li[data-run="r-dead"] .live-marker.silent');
  await marker.waitFor({ timeout: 5000 });
  assert.equal(await marker.innerText(), '● silent');
});

test('the page loaded nothing from anywhere else', () => {
  assert.deepEqual(foreign, []);
});
