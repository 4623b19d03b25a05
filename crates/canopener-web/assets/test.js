// The test page and a run's page: start a run, follow every run's progress on /api/runs/events
// (started, progress with each verdict as its test ends, finished), and show the report at the end.
// A page that shows no run yet follows the next one anybody starts.
'use strict';
(function () {
  const page = canopener.runs = {
    received: 0, shown: null, verdicts: new Map(), finished: new Set(), connected: false,
  };
  const $ = (id) => document.getElementById(id);
  const box = $('run');
  const fixed = box && box.dataset.run ? Number(box.dataset.run) : null;

  function refuse(message) {
    const p = $('refusal');
    if (!p) return;
    p.textContent = message;
    p.hidden = message === null;
  }

  function row(v) {
    return canopener.el('tr', { 'data-test': v.test, 'data-verdict': v.verdict },
      canopener.el('td', { class: 'mono' }, v.test), canopener.el('td', {}, v.title),
      canopener.el('td', {}, canopener.el('span', { class: 'verdict ' + v.verdict }, v.verdict)),
      canopener.el('td', {}, v.reason));
  }

  function finishedView(view) {
    const done = box.querySelector('.ended');
    done.hidden = false;
    done.dataset.status = view.status;
    done.replaceChildren(canopener.el('p', {}, 'Run ' + view.id + ' ' + view.status
      + (view.message ? ': ' + view.message : '') + '.'));
    if (view.status !== 'failed') {
      done.append(canopener.el('p', {}, canopener.el('a', { href: '/runs/' + view.id + '/report', class: 'report-link' },
        'Open the HTML report'), ' · ', canopener.el('a', { href: '/runs/' + view.id + '/report.json' }, 'JSON'),
      view.previous ? ' · ' : null, view.previous ? canopener.el('a', {
        class: 'compare', href: '/compare?a=' + view.previous + '&b=' + view.id,
      }, 'what changed since run ' + view.previous) : null),
      canopener.el('iframe', { class: 'report', src: '/runs/' + view.id + '/report', title: 'report of run ' + view.id }));
    }
    box.querySelector('.current').textContent = '';
  }

  async function show(id) {
    page.shown = id;
    const [ok, view] = await canopener.request('GET', '/api/runs/' + id);
    if (!ok || page.shown !== id) return;
    box.hidden = false;
    box.dataset.run = id;
    const seen = new Set(view.verdicts.map((v) => v.test));
    page.verdicts.set(id, seen);
    box.replaceChildren(
      canopener.el('h2', {}, 'Run ' + id + ': node ' + view.node + ' on ' + view.bus + ', ' + view.eds),
      canopener.el('progress', { max: view.total, value: view.verdicts.length }),
      canopener.el('p', { class: 'current' }, view.current ? 'running ' + view.current : ''),
      view.status === 'running' ? canopener.el('button', { type: 'button', class: 'stop' }, 'Stop') : '',
      canopener.el('div', { class: 'ended', hidden: '' }),
      canopener.el('table', { class: 'verdicts' }, canopener.el('tbody', {}, ...view.verdicts.map(row))));
    const stop = box.querySelector('button.stop');
    if (stop) stop.addEventListener('click', () => canopener.request('POST', '/api/runs/' + id + '/stop'));
    if (view.status !== 'running') { page.finished.add(id); finishedView(view); }
  }

  function progress(event) {
    if (event.run !== page.shown) return;
    const bar = box.querySelector('progress');
    if (bar) { bar.max = event.total; bar.value = event.done; }
    box.querySelector('.current').textContent = event.current ? 'running ' + event.current : '';
    const seen = page.verdicts.get(event.run);
    if (event.verdict && seen && !seen.has(event.verdict.test)) {
      seen.add(event.verdict.test);
      box.querySelector('tbody').append(row(event.verdict));
    }
  }

  function running(event) {
    const list = $('running');
    if (!list) return;
    if (event.event === 'started') {
      list.append(canopener.el('li', { 'data-run': event.run }, canopener.el('a', { href: '/runs/' + event.run },
        'run ' + event.run), ': node ' + event.node + ' on ' + event.bus));
    } else if (event.event === 'finished') {
      const item = list.querySelector('[data-run="' + event.run + '"]');
      if (item) item.remove();
    }
  }

  const source = new EventSource('/api/runs/events');
  source.onmessage = (message) => {
    page.received += 1;
    const event = JSON.parse(message.data);
    running(event);
    if (event.event === 'started' && fixed === null && (page.shown === null || page.finished.has(page.shown))) {
      show(event.run);
    } else if (event.event === 'progress') {
      progress(event);
    } else if (event.event === 'finished' && event.run === page.shown) {
      page.finished.add(event.run);
      show(event.run);
    }
  };
  source.onopen = () => { page.connected = true; };
  if (fixed !== null) show(fixed);

  const form = $('start');
  if (form) {
    const bus = $('bus');
    const faultLabel = $('fault-label');
    const syncFault = () => { faultLabel.hidden = bus.value !== 'simulated'; };
    bus.addEventListener('change', syncFault);
    syncFault();
    form.addEventListener('submit', async (e) => {
      e.preventDefault();
      refuse(null);
      let eds = $('eds').value;
      const file = $('upload').files[0];
      if (file) {
        const [ok, body] = await canopener.request('POST', '/api/eds?name=' + encodeURIComponent(file.name), file);
        if (!ok) { refuse(body.error); return; }
        eds = body.eds;
      }
      page.start({
        bus: bus.value, node: Number($('node').value), eds,
        suites: [...document.querySelectorAll('input[name="suite"]:checked')].map((i) => i.value),
        fault: bus.value === 'simulated' ? $('fault').value : null,
      });
    });
  }

  // Starts a run; shows it, or why it was refused.
  page.start = async function (request) {
    const [ok, body] = await canopener.request('POST', '/api/runs', JSON.stringify(request),
      { 'content-type': 'application/json' });
    if (!ok) { refuse(body.error); return null; }
    show(body.run);
    return body.run;
  };
})();
