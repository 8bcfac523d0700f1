// Fenestra dashboard: jobs and sites of the signed-in user, a job's progress, plot and
// report, and job submission, over fenestrad's JSON API (README.md beside this file).
// Server data goes into the page as text only (textContent, createElement), never as HTML.
'use strict';

const TOKEN_KEY = 'fenestra.token';
const POLL_MS = 1000;
const VIEWS = ['sign-in', 'list-view', 'job-view', 'submit-view'];
const ACTIVE = new Set(['JOB_STATE_QUEUED', 'JOB_STATE_RUNNING']);
const FIELD_ERRORS = { job: 'job-file-error', scene: 'scene-file-error', weather: 'weather-file-error' };
const JOB_COLUMNS = { name: 'Name', owner: 'Owner', state: 'State', evaluations: 'Evaluations',
  best: 'Best', elapsed: 'Elapsed', remaining: 'Remaining', actions: '' };
const SVG_NS = 'http://www.w3.org/2000/svg';

const $ = (id) => document.getElementById(id);

// What the page holds. `gen` counts view changes: an answer that comes back after the view
// changed (or the user signed out) is dropped, and its poll not rescheduled.
const state = {
  me: null,
  gen: 0,
  timer: 0,
  waiting: null, // a poll held back while the tab is hidden
  deleted: new Set(), // ids deleted here, kept out of polls answered meanwhile
  series: null, // the open job's progress snapshots: {best: [[x, y]], dots: [[x, y]]}
  reportUrl: '',
};

// ---- API ----

class ApiError extends Error {
  constructor(status, code, message, field) {
    super(message);
    Object.assign(this, { name: 'ApiError', status, code, field });
  }
}

// sessionStorage only; `undefined` reads, '' removes. False when the browser refuses it.
function tokenStore(value) {
  try {
    if (value === undefined) return sessionStorage.getItem(TOKEN_KEY) || '';
    if (value) sessionStorage.setItem(TOKEN_KEY, value);
    else sessionStorage.removeItem(TOKEN_KEY);
    return true;
  } catch {
    return value === undefined ? '' : false;
  }
}

// Calls the API with the bearer token; resolves to the parsed JSON (or the text of another
// content type), throws ApiError. A 401 answer signs out first.
async function api(method, path, body) {
  const init = { method, headers: { Authorization: `Bearer ${tokenStore()}` }, cache: 'no-store' };
  if (body !== undefined) {
    init.headers['Content-Type'] = 'application/json';
    init.body = JSON.stringify(body);
  }
  let res;
  let data;
  try {
    res = await fetch(path, init);
    data = await res.text();
  } catch {
    throw new ApiError(0, 'UNAVAILABLE', 'The server cannot be reached.', '');
  }
  if ((res.headers.get('Content-Type') || '').includes('json')) {
    try { data = data ? JSON.parse(data) : {}; } catch { data = null; }
  }
  if (res.ok) return data;
  const e = data && typeof data === 'object' ? data : {};
  const err = new ApiError(res.status, e.code || `HTTP_${res.status}`,
    e.message || `The server answered ${res.status} ${res.statusText}`.trim(), e.field || '');
  if (res.status === 401) signOut(err.message);
  throw err;
}

// Resolves to [value, null] or [undefined, error]: error handling without try blocks.
const settle = (promise) => promise.then((v) => [v, null], (e) => [undefined, e]);
const jobPath = (id, tail = '') => `/api/v1/jobs/${encodeURIComponent(id)}${tail}`;

// ---- DOM and formatting helpers ----

function make(tag, className, text) {
  const e = document.createElement(tag);
  if (className) e.className = className;
  if (text !== undefined) e.textContent = text;
  return e;
}

function svg(tag, attrs, text) {
  const e = document.createElementNS(SVG_NS, tag);
  for (const [k, v] of Object.entries(attrs)) e.setAttribute(k, String(v));
  if (text !== undefined) e.textContent = text;
  return e;
}

function setText(e, text) {
  if (e && e.textContent !== text) e.textContent = text;
}

function button(label, className, onClick) {
  const b = make('button', className, label);
  b.type = 'button';
  b.addEventListener('click', () => onClick(b));
  return b;
}

// Shows an error's message in `e`; after a 401 the sign-in form already shows it.
function showError(e, err) {
  if (err.status !== 401) setText(e, err.message || String(err));
}

const num = (x) => Number(x) || 0;
const pad2 = (n) => String(n).padStart(2, '0');
// "JOB_STATE_RUNNING" -> "running"
const words = (value, prefix) => (value && value.startsWith(prefix) ? value.slice(prefix.length).toLowerCase() : 'unknown');

function formatSeconds(seconds) {
  const t = Math.max(0, Math.round(num(seconds)));
  if (t < 60) return `${t} s`;
  if (t < 3600) return `${Math.floor(t / 60)} min ${pad2(t % 60)} s`;
  return `${Math.floor(t / 3600)} h ${pad2(Math.floor((t % 3600) / 60))} min`;
}

const formatEstimate = (e) => `${num(e.value).toFixed(2)} ± ${num(e.standardError).toFixed(2)} %`;

function stateText(job) {
  const w = words(job.state, 'JOB_STATE_');
  return job.cancelRequested && ACTIVE.has(job.state) ? `${w} (cancelling)` : w;
}

// The numbers a list row and the job page show.
function summary(job) {
  const p = job.progress || {};
  const r = job.result || {};
  const best = p.best && num(p.evaluations) > 0 ? p.best.value || {} : r.bestValue;
  return {
    evaluations: num(p.evaluations) || num(r.evaluations),
    max: num(p.maxEvaluations),
    best: best ? formatEstimate(best) : '—',
    elapsed: job.progress ? formatSeconds(p.elapsedSeconds) : '—',
    remaining: job.state === 'JOB_STATE_RUNNING' && job.progress ? formatSeconds(p.remainingSeconds) : '—',
  };
}

function setProgress(bar, done, max) {
  bar.max = max > 0 ? max : 1;
  bar.value = Math.min(done, bar.max);
  const text = max > 0 ? `${done} / ${max}` : String(done);
  setText(bar, text);
  bar.title = `${text} evaluations`;
}

// ---- Views, routing and polling ----

function stopPolling() {
  clearTimeout(state.timer);
  state.timer = 0;
  state.waiting = null;
}

// Runs `fn` POLL_MS after the previous answer, held while the tab is hidden.
function schedule(gen, fn) {
  if (gen !== state.gen) return;
  clearTimeout(state.timer);
  state.timer = setTimeout(() => {
    if (gen !== state.gen) return;
    if (document.hidden) state.waiting = fn;
    else fn();
  }, POLL_MS);
}

function showView(id, title) {
  for (const v of VIEWS) $(v).hidden = v !== id;
  $('loading').hidden = id !== null;
  if (title) document.title = `Fenestra: ${title}`;
}

function route() {
  stopPolling();
  const gen = ++state.gen;
  clearJobView();
  if (!tokenStore()) return showSignIn('');
  if (!state.me) return loadMe(gen);
  const hash = location.hash || '#/';
  const job = /^#\/jobs\/([^/?#]+)$/.exec(hash);
  if (job) return showJob(decodePart(job[1]), gen);
  if (hash === '#/submit') return showSubmit();
  return showList(gen);
}

function decodePart(s) {
  try { return decodeURIComponent(s); } catch { return s; }
}

// ---- Sign in and out ----

function showSignIn(message) {
  showView('sign-in', 'sign in');
  setText($('sign-in-error'), message);
  $('user').hidden = true;
  $('sign-out').hidden = true;
  $('token').focus();
}

async function loadMe(gen) {
  showView(null);
  const [answer, err] = await settle(api('GET', '/api/v1/me'));
  if (gen !== state.gen) return;
  if (err) return err.status === 401 || showSignIn(err.message);
  const me = (state.me = answer || {});
  setText($('user'), `${me.name || ''}${me.admin ? ' (administrator)' : ''}`);
  $('user').hidden = false;
  $('sign-out').hidden = false;
  $('jobs').querySelector('th.owner').hidden = !me.admin;
  return route();
}

// Forgets the token and everything shown for its user; shows the sign-in form.
function signOut(message) {
  tokenStore('');
  state.me = null;
  state.deleted.clear();
  stopPolling();
  state.gen++;
  clearJobView();
  $('jobs').tBodies[0].replaceChildren();
  $('sites').tBodies[0].replaceChildren();
  $('submit-form').reset();
  showSignIn(message);
}

function onSignIn(ev) {
  ev.preventDefault();
  const value = $('token').value.trim();
  if (!value) return setText($('sign-in-error'), 'Paste your API token.');
  if (!tokenStore(value)) return setText($('sign-in-error'), 'This browser refuses session storage.');
  $('token').value = '';
  setText($('sign-in-error'), '');
  return route();
}

// ---- The list ----

function showList(gen) {
  showView('list-view', 'jobs');
  pollList(gen);
}

async function pollList(gen) {
  try {
    const [jobs, sites] = await Promise.all([api('GET', '/api/v1/jobs'), api('GET', '/api/v1/sites')]);
    if (gen !== state.gen) return;
    syncRows('jobs', (jobs && jobs.jobs) || [], 'jobId', jobRow, updateJobRow);
    syncRows('sites', (sites && sites.sites) || [], 'siteId', siteRow, updateSiteRow);
    setText($('list-error'), '');
  } catch (err) {
    if (gen !== state.gen || err.status === 401) return;
    showError($('list-error'), err);
  }
  schedule(gen, () => pollList(gen));
}

// Makes table #<table> hold one row per item, in order, reusing the rows of known ids so
// that buttons and focus survive a poll.
function syncRows(table, items, key, create, update) {
  const tbody = $(table).tBodies[0];
  const rows = new Map([...tbody.rows].map((r) => [r.dataset[key], r]));
  let next = tbody.firstElementChild;
  for (const item of items) {
    if (state.deleted.has(item.id)) continue;
    let row = rows.get(item.id);
    if (row) rows.delete(item.id);
    else row = create(item.id);
    update(row, item);
    if (row === next) next = next.nextElementSibling;
    else tbody.insertBefore(row, next);
  }
  for (const row of rows.values()) row.remove();
  updateEmpty(table);
}

function updateEmpty(table) {
  $(`${table}-empty`).hidden = $(table).tBodies[0].rows.length > 0;
}

function jobRow(id) {
  const row = make('tr');
  row.dataset.jobId = id;
  for (const [c, label] of Object.entries(JOB_COLUMNS)) {
    if (c === 'owner' && !state.me.admin) continue;
    const td = row.appendChild(make('td', c));
    if (label) td.dataset.label = label; // shown on narrow screens (app.css)
  }
  row.querySelector('td.evaluations').append(make('progress', 'progress'));
  row.querySelector('td.actions').append(button('Open', 'open', () => {
    location.hash = `#/jobs/${encodeURIComponent(id)}`;
  }));
  return row;
}

function updateJobRow(row, job) {
  const s = summary(job);
  const cell = (c) => row.querySelector(`td.${c}`);
  setText(cell('name'), job.name || '(unnamed)');
  cell('name').title = job.id;
  if (cell('owner')) setText(cell('owner'), job.owner || '');
  setText(cell('state'), stateText(job));
  cell('state').title = job.state === 'JOB_STATE_QUEUED'
    ? `${num(job.queuePosition)} ahead in the queue` : job.error || job.stage || '';
  setProgress(row.querySelector('progress'), s.evaluations, s.max);
  setText(cell('best'), s.best);
  setText(cell('elapsed'), s.elapsed);
  setText(cell('remaining'), s.remaining);
  const active = ACTIVE.has(job.state);
  const cancel = toggleButton(cell('actions'), 'cancel', 'Cancel', active, (b) => cancelJob(job.id, b));
  if (cancel) cancel.disabled = !!job.cancelRequested;
  toggleButton(cell('actions'), 'delete', 'Delete', !active,
    (b) => deleteRow(job.id, jobPath(job.id), b));
}

// Makes `cell` hold button.<className> or not; returns it when it is there.
function toggleButton(cell, className, label, show, onClick) {
  let b = cell.querySelector(`button.${className}`);
  if (show && !b) return cell.appendChild(button(label, className, onClick));
  if (!show && b) b.remove();
  return show ? b : null;
}

// Runs an action of a list row's button; its answer's error shows above the tables.
async function rowAction(b, action) {
  b.disabled = true;
  const [, err] = await settle(action());
  b.disabled = !err; // on success the row is updated or gone
  if (err) showError($('list-error'), err);
  else setText($('list-error'), '');
}

function cancelJob(id, b) {
  return rowAction(b, async () => {
    const info = await api('POST', jobPath(id, '/cancel'));
    const row = b.closest('tr');
    if (row && info) updateJobRow(row, info);
  });
}

function deleteRow(id, path, b) {
  return rowAction(b, async () => {
    await api('DELETE', path);
    state.deleted.add(id);
    const table = b.closest('table');
    b.closest('tr').remove();
    if (table) updateEmpty(table.id);
  });
}

function siteRow(id) {
  const row = make('tr');
  row.dataset.siteId = id;
  for (const c of ['name', 'owner', 'state', 'actions']) row.append(make('td', c));
  row.lastChild.append(button('Delete', 'delete',
    (b) => deleteRow(id, `/api/v1/sites/${encodeURIComponent(id)}`, b)));
  return row;
}

function updateSiteRow(row, site) {
  const cell = (c) => row.querySelector(`td.${c}`);
  setText(cell('name'), site.name || site.id);
  cell('name').title = [site.id, site.weatherName].filter(Boolean).join(', ');
  setText(cell('owner'), site.owner || '');
  setText(cell('state'), words(site.state, 'SITE_STATE_'));
  cell('state').title = site.error || '';
}

// ---- The job page ----

function clearJobView() {
  const texts = '#job-title, dd[id], #job-error, #job-evaluations, #job-report-status';
  for (const e of $('job-view').querySelectorAll(texts)) e.replaceChildren();
  $('job-details').hidden = true;
  $('job-owner-row').hidden = true;
  $('job-plot').replaceChildren();
  $('job-report').hidden = true;
  const frame = $('job-report').querySelector('iframe');
  if (frame) frame.remove();
  const link = $('job-report-download');
  link.hidden = true;
  link.removeAttribute('href');
  if (state.reportUrl) URL.revokeObjectURL(state.reportUrl);
  state.reportUrl = '';
  state.series = null;
}

function showJob(id, gen) {
  showView('job-view', id);
  setText($('job-title'), id);
  $('job-cancel').dataset.jobId = id;
  state.series = { best: [], dots: [] };
  pollJob(id, gen);
}

async function pollJob(id, gen) {
  const [job, err] = await settle(api('GET', jobPath(id)));
  if (gen !== state.gen || (err && err.status === 401)) return;
  if (err && err.status === 404) {
    $('job-details').hidden = true;
    return setText($('job-error'), 'No such job');
  }
  if (err) {
    showError($('job-error'), err);
    return schedule(gen, () => pollJob(id, gen));
  }
  renderJob(job);
  if (ACTIVE.has(job.state)) schedule(gen, () => pollJob(id, gen));
  else if (job.result) loadReport(id, gen);
}

function renderJob(job) {
  const s = summary(job);
  $('job-title').replaceChildren(job.name || '(unnamed)', ' ', make('span', 'job-id', `(${job.id})`));
  document.title = `Fenestra: ${job.name || job.id}`;
  setText($('job-state'), stateText(job));
  setText($('job-stage'), job.state === 'JOB_STATE_QUEUED'
    ? `waiting, ${num(job.queuePosition)} ahead in the queue` : job.stage || '—');
  setText($('job-owner'), job.owner || '');
  $('job-owner-row').hidden = !job.owner;
  setProgress($('job-progress'), s.evaluations, s.max);
  setText($('job-evaluations'), s.max > 0 ? `${s.evaluations} of ${s.max}` : String(s.evaluations));
  setText($('job-best'), s.best);
  setText($('job-elapsed'), s.elapsed);
  setText($('job-remaining'), s.remaining);
  const created = num(job.createdUnixMs);
  setText($('job-created'), created ? new Date(created).toLocaleString() : '—');
  setText($('job-error'), job.error || '');
  $('job-cancel').hidden = !ACTIVE.has(job.state);
  $('job-cancel').disabled = !!job.cancelRequested;
  $('job-details').hidden = false;
  const hist = job.result && job.result.history;
  if (hist && hist.length) drawHistory(hist, Math.max(s.max, num(job.result.evaluations)));
  else drawSnapshots(job.progress, s.max);
}

async function onCancelJob() {
  const b = $('job-cancel');
  const gen = state.gen;
  b.disabled = true;
  const [info, err] = await settle(api('POST', jobPath(b.dataset.jobId, '/cancel')));
  if (gen !== state.gen) return;
  if (info) renderJob(info);
  if (err) {
    b.disabled = false;
    showError($('job-error'), err);
  }
}

// Adds a poll's progress to the series (one point per evaluation count) and draws it.
function drawSnapshots(p, max) {
  const series = state.series || { best: [], dots: [] };
  if (p && num(p.evaluations) > 0 && p.best) {
    const x = num(p.evaluations);
    const put = (list, y) => {
      const last = list[list.length - 1];
      if (last && last[0] === x) last[1] = y;
      else list.push([x, y]);
    };
    put(series.best, num(p.best.value && p.best.value.value));
    if (p.current) put(series.dots, num(p.current.value && p.current.value.value));
  }
  drawPlot(series.best, series.dots, max);
}

// The result's search: each evaluation as a dot, the best so far as a line.
function drawHistory(history, max) {
  const dots = history.map((e, i) => [i + 1, num(e.value && e.value.value)]);
  const best = dots.filter((d, i) => i === 0 || history[i].improved);
  const last = best[best.length - 1];
  if (last[0] < dots.length) best.push([dots.length, last[1]]);
  drawPlot(best, dots, max);
}

// Round tick values over [lo, hi], with their labels.
function ticks(lo, hi, count, integer) {
  const raw = (hi - lo) / count;
  const p = 10 ** Math.floor(Math.log10(raw));
  const f = raw / p;
  let step = (f < 1.5 ? 1 : f < 3 ? 2 : f < 7 ? 5 : 10) * p;
  if (integer) step = Math.max(1, Math.round(step));
  const decimals = integer ? 0 : Math.max(0, -Math.floor(Math.log10(step)));
  const out = [];
  for (let t = Math.ceil(lo / step) * step; t <= hi + step * 1e-9; t += step) out.push([t, t.toFixed(decimals)]);
  return out;
}

function drawPlot(best, dots, max) {
  const box = $('job-plot');
  const points = best.concat(dots);
  if (!points.length) {
    box.replaceChildren(make('p', 'plot-empty muted', 'The plot appears after the first evaluation.'));
    return;
  }
  const W = 600, H = 240, L = 58, R = 14, T = 12, B = 42;
  const ys = points.map((pt) => pt[1]);
  const xHi = Math.max(max, 1, ...points.map((pt) => pt[0]));
  let yLo = Math.min(...ys), yHi = Math.max(...ys);
  const margin = yHi - yLo > 1e-9 ? (yHi - yLo) * 0.08 : Math.max(Math.abs(yHi) * 0.01, 0.5);
  yLo -= margin;
  yHi += margin;
  const sx = (x) => (L + (x / xHi) * (W - L - R)).toFixed(1);
  const sy = (y) => (T + ((yHi - y) / (yHi - yLo)) * (H - T - B)).toFixed(1);
  const root = svg('svg', { width: '100%', viewBox: `0 0 ${W} ${H}`, role: 'img', class: 'plot-svg',
    'aria-label': `Best value so far against evaluations done, up to ${Math.max(...points.map((pt) => pt[0]))}` });
  for (const [t, label] of ticks(yLo, yHi, 5, false)) {
    root.append(svg('line', { x1: L, x2: W - R, y1: sy(t), y2: sy(t), class: 'plot-grid' }),
      svg('text', { x: L - 6, y: sy(t), class: 'plot-tick plot-tick-y' }, label));
  }
  for (const [t, label] of ticks(0, xHi, 6, true)) {
    root.append(svg('line', { x1: sx(t), x2: sx(t), y1: H - B, y2: H - B + 4, class: 'plot-axis' }),
      svg('text', { x: sx(t), y: H - B + 16, class: 'plot-tick plot-tick-x' }, label));
  }
  root.append(
    svg('line', { x1: L, x2: W - R, y1: H - B, y2: H - B, class: 'plot-axis' }),
    svg('line', { x1: L, x2: L, y1: T, y2: H - B, class: 'plot-axis' }),
    svg('text', { x: (L + W - R) / 2, y: H - 6, class: 'plot-label' }, 'evaluations'),
    svg('text', { x: 0, y: 0, class: 'plot-label', transform: `translate(14 ${(T + H - B) / 2}) rotate(-90)` },
      'value [%]'));
  for (const [x, y] of dots) root.append(svg('circle', { cx: sx(x), cy: sy(y), r: 2.5, class: 'plot-dot' }));
  // The best value as steps: it holds until the next improvement
  const line = best.flatMap(([x, y], i) => (i ? [`${sx(x)},${sy(best[i - 1][1])}`] : []).concat(`${sx(x)},${sy(y)}`));
  root.append(svg('polyline', { points: line.join(' '), class: 'plot-best' }));
  box.replaceChildren(root);
}

async function loadReport(id, gen) {
  const status = $('job-report-status');
  $('job-report').hidden = false;
  setText(status, 'Loading the report…');
  const [answer, err] = await settle(api('GET', jobPath(id, '/report')));
  if (gen !== state.gen) return;
  if (err) return showError(status, err);
  const html = typeof answer === 'string' ? answer : JSON.stringify(answer);
  setText(status, '');
  // No allow-* tokens: no scripts, an opaque origin, no navigation of this page
  const frame = make('iframe', 'report-frame');
  frame.setAttribute('sandbox', '');
  frame.title = 'report';
  frame.srcdoc = html;
  $('job-report').append(frame);
  state.reportUrl = URL.createObjectURL(new Blob([html], { type: 'text/html' }));
  const link = $('job-report-download');
  link.href = state.reportUrl;
  link.download = `${id}-report.html`;
  link.hidden = false;
}

// ---- Submission ----

function showSubmit() {
  showView('submit-view', 'new job');
  clearSubmitErrors();
}

function clearSubmitErrors() {
  for (const id of [...Object.values(FIELD_ERRORS), 'submit-error']) setText($(id), '');
}

// The file's JSON object, or undefined after showing why not next to its field.
async function readJson(file, errorId) {
  let value;
  try {
    value = JSON.parse(await file.text());
  } catch (err) {
    setText($(errorId), `${file.name} is not valid JSON: ${err.message}`);
    return undefined;
  }
  if (value && typeof value === 'object' && !Array.isArray(value)) return value;
  setText($(errorId), `${file.name} must hold a JSON object.`);
  return undefined;
}

// Base64 of the bytes, converted in chunks so that no huge argument list is built.
function base64(buffer) {
  const bytes = new Uint8Array(buffer);
  const parts = [];
  for (let i = 0; i < bytes.length; i += 0x8000) {
    parts.push(String.fromCharCode.apply(null, bytes.subarray(i, i + 0x8000)));
  }
  return btoa(parts.join(''));
}

// The POST /api/v1/jobs body from the chosen files, or null after showing what is wrong.
async function buildRequest() {
  const [jobFile, sceneFile, weatherFile] = ['job-file', 'scene-file', 'weather-file'].map((id) => $(id).files[0]);
  if (!jobFile) {
    setText($('job-file-error'), 'Choose a job file.');
    return null;
  }
  const job = await readJson(jobFile, 'job-file-error');
  const scene = sceneFile ? await readJson(sceneFile, 'scene-file-error') : null;
  if (!job || scene === undefined) return null;
  // Paths on this computer mean nothing to the server: the files themselves are sent
  for (const key of ['sceneFile', 'scene_file', 'weatherFile', 'weather_file']) delete job[key];
  const body = { job };
  if (scene) body.scene = scene;
  if (weatherFile) {
    try {
      body.weatherEpw = base64(await weatherFile.arrayBuffer());
    } catch (err) {
      setText($('weather-file-error'), `${weatherFile.name} cannot be read: ${err.message}`);
      return null;
    }
    body.weatherName = weatherFile.name;
  }
  return body;
}

async function onSubmit(ev) {
  ev.preventDefault();
  const gen = state.gen;
  const b = $('submit');
  clearSubmitErrors();
  b.disabled = true;
  try {
    const body = await buildRequest();
    if (!body || gen !== state.gen) return;
    const info = await api('POST', '/api/v1/jobs', body);
    if (gen !== state.gen) return;
    $('submit-form').reset();
    location.hash = `#/jobs/${encodeURIComponent(info.id)}`;
  } catch (err) {
    if (gen === state.gen) showError($(FIELD_ERRORS[err.field] || 'submit-error'), err);
  } finally {
    b.disabled = false;
  }
}

// ---- Start ----

function start() {
  $('sign-in').addEventListener('submit', onSignIn);
  $('sign-out').addEventListener('click', () => {
    signOut('');
    if (location.hash && location.hash !== '#/') history.replaceState(null, '', '#/');
  });
  $('submit-form').addEventListener('submit', onSubmit);
  $('job-back').addEventListener('click', () => {
    location.hash = '#/';
  });
  $('job-cancel').addEventListener('click', onCancelJob);
  window.addEventListener('hashchange', route);
  document.addEventListener('visibilitychange', () => {
    const fn = state.waiting;
    if (document.hidden || !fn) return;
    state.waiting = null;
    fn();
  });
  route();
}

start();
