// The system monitor page: follows /api/events (the JSON events of `canopener net monitor --format
// json`, numbered by the server) on top of the state /api/state gives, and keeps the page contract:
// data-state on every device badge, data-suspect on cables and devices, one diagnosis element per
// explanation with data-kind and data-candidates.
'use strict';
(function () {
  const live = canopener.monitor = {
    received: 0,       // server-sent events received
    applied: 0,        // events applied (after the snapshot)
    lastSeq: 0,        // the number of the last event applied
    latencies: [],     // ms from the monitor's event (its time) to its arrival here
    startedUnixMs: null,
    gaps: 0,           // events whose number did not follow the one before (lost on the way)
    raw: [],           // the last events as received (the JSON text of each server-sent event)
    connected: false,
    ready: false,
  };
  let lastReceived = null;
  const diagnoses = new Map(); // network -> explanations
  let supplies = {};
  let pending = [];
  let ready = false;
  const MAX_LOG = 300;

  const STATES = ['boot-up', 'pre-operational', 'operational', 'stopped', 'silent'];
  function contractState(state) { return STATES.includes(state) ? state : 'unknown'; }

  function setState(node, network, state) {
    for (const badge of document.querySelectorAll('.state[data-network="' + network + '"]')) {
      if (badge.getAttribute('data-device') !== node) continue;
      badge.setAttribute('data-state', contractState(state));
      const title = badge.querySelector('title');
      if (title) title.textContent = node + ' on network ' + network + ': ' + (state || 'unknown');
    }
  }

  function log(text, cls) {
    const list = document.getElementById('events');
    list.prepend(canopener.el('li', { class: cls }, text));
    while (list.children.length > MAX_LOG) list.lastChild.remove();
  }

  function drawDiagnosis() {
    const suspectCables = new Set();
    const suspectDevices = new Set();
    const panel = document.getElementById('explanations');
    panel.replaceChildren();
    for (const [network, explanations] of [...diagnoses.entries()].sort((a, b) => a[0] - b[0])) {
      for (const e of explanations) {
        if (e.kind === 'cable') e.candidates.forEach((c) => suspectCables.add(c));
        if (e.kind === 'device') e.candidates.forEach((c) => suspectDevices.add(c));
        if (e.kind === 'supply') {
          for (const [device, domains] of Object.entries(supplies)) {
            if (domains.some((d) => e.candidates.includes(d))) suspectDevices.add(device);
          }
        }
        panel.append(canopener.el('li', {
          class: 'explanation', 'data-kind': e.kind, 'data-network': network,
          'data-candidates': e.candidates.join(','), 'data-explains': e.explains.join(','),
        }, canopener.el('b', {}, e.kind), ' ' + e.candidates.join(' or '),
        ' (network ' + network + ') explains ' + e.explains.join(', ')));
      }
    }
    for (const cable of document.querySelectorAll('[data-cable]')) {
      cable.setAttribute('data-suspect', String(suspectCables.has(cable.getAttribute('data-cable'))));
    }
    for (const vertex of document.querySelectorAll('.vertex[data-suspect]')) {
      vertex.setAttribute('data-suspect', String(suspectDevices.has(vertex.getAttribute('data-name'))));
    }
    document.getElementById('all-heard').hidden = panel.children.length > 0 || diagnoses.size === 0;
  }

  // Applies an event to the page and logs it; `logOnly` for events the state already includes.
  function apply(event, logOnly) {
    const t = event.time.toFixed(3) + ' s  net ' + event.network + '  ';
    if (event.event === 'state') {
      if (!logOnly) setState(event.node, event.network, event.state);
      log(t + event.node + ' (node ' + event.node_id + '): ' + event.state, event.state);
    } else if (event.event === 'recovered') {
      log(t + event.node + ' (node ' + event.node_id + ') is heard again', 'recovered');
    } else if (event.event === 'diagnosis') {
      if (!logOnly) { diagnoses.set(event.network, event.explanations); drawDiagnosis(); }
      log(event.silent.length === 0 ? t + 'every device is heard'
        : t + 'silent: ' + event.silent.join(', ') + '; ' + event.explanations.map(
          (e) => e.kind + ' ' + e.candidates.join(' or ')).join('; '), 'diagnosis');
    }
  }

  function applySnapshot(state) {
    supplies = state.supplies || {};
    live.startedUnixMs = state.started_unix_ms;
    const snapshot = state.snapshot;
    if (snapshot) {
      for (const d of snapshot.devices) {
        if (!d.is_monitor) { setState(d.node, d.network, d.state); continue; }
        // The monitor's own vertex is not watched: its badge says where the monitor listens.
        for (const badge of document.querySelectorAll('.state[data-network="' + d.network + '"]')) {
          if (badge.getAttribute('data-device') !== d.node) continue;
          badge.setAttribute('data-monitor', 'true');
          const title = badge.querySelector('title');
          if (title) title.textContent = d.node + ' on network ' + d.network + ': the monitor listens here';
        }
      }
      diagnoses.clear();
      for (const n of snapshot.diagnoses) if (n.last) diagnoses.set(n.network, n.last.explanations);
      drawDiagnosis();
    }
    live.lastSeq = state.seq;
  }

  function receive(message) {
    live.received += 1;
    const seq = Number(message.lastEventId);
    if (lastReceived !== null && seq !== lastReceived + 1) live.gaps += 1;
    lastReceived = seq;
    live.raw.push(message.data);
    if (live.raw.length > 20000) live.raw.shift();
    const event = JSON.parse(message.data);
    if (live.startedUnixMs !== null) {
      live.latencies.push(Date.now() - (live.startedUnixMs + event.time * 1000));
      if (live.latencies.length > 100000) live.latencies.shift();
    }
    if (!ready) { pending.push([seq, event]); return; }
    if (seq <= live.lastSeq) return;
    live.lastSeq = seq;
    live.applied += 1;
    apply(event, false);
  }

  async function load() {
    const [ok, state] = await canopener.request('GET', '/api/state');
    const connection = document.getElementById('connection');
    if (!ok) { connection.textContent = state.error; return; }
    applySnapshot(state);
    if (document.getElementById('events').children.length === 0) {
      for (const event of state.recent || []) apply(event, true);
    }
    for (const [seq, event] of pending) {
      if (seq > live.lastSeq) { live.lastSeq = seq; live.applied += 1; apply(event, false); }
    }
    pending = [];
    ready = true;
    live.ready = true;
    connection.dataset.connection = state.status.startsWith('failed') ? 'lost' : 'live';
    connection.textContent = state.status.startsWith('failed') ? state.status : 'live: monitor ' + state.status;
  }

  const source = new EventSource('/api/events');
  source.onmessage = receive;
  // On every (re)connection: the state again, then the events after it (a reconnection resumes
  // with Last-Event-ID; whatever the server no longer kept is in the state).
  source.onopen = () => { ready = false; live.ready = false; live.connected = true; load(); };
  source.onerror = () => {
    const connection = document.getElementById('connection');
    connection.dataset.connection = 'lost';
    connection.textContent = 'connection lost: reconnecting…';
  };
})();
