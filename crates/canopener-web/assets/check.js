// The check page: a dropped or chosen file goes to /api/check; the findings come back as the
// document of `canopener eds check --format json` with the lines they point at, and the safe fixes
// as a diff. Every finding element carries data-code, data-severity and data-line.
'use strict';
(function () {
  const page = canopener.check = { report: null, refusal: null, file: null };
  const $ = (id) => document.getElementById(id);

  function refuse(message) {
    page.refusal = message;
    $('refusal').textContent = message;
    $('refusal').hidden = false;
    $('result').hidden = true;
  }

  function marked(line, column, length) {
    // Columns count characters (code points), as the report's JSON does.
    const chars = Array.from(line || '');
    const start = Math.max(0, column - 1);
    const end = Math.min(chars.length, start + Math.max(length, 1));
    return [chars.slice(0, start).join(''), canopener.el('mark', {}, chars.slice(start, end).join('') || ' '),
      chars.slice(end).join('')];
  }

  function filter() {
    const severities = new Set([...document.querySelectorAll('#severities input:checked')].map((i) => i.value));
    const code = $('code').value;
    for (const item of document.querySelectorAll('#findings .finding')) {
      item.hidden = !severities.has(item.dataset.severity) || (code !== '' && item.dataset.code !== code);
    }
  }

  function show(name, checked) {
    page.checked = checked;
    page.report = checked.report;
    const file = checked.report.files[0];
    const summary = checked.report.summary;
    $('refusal').hidden = true;
    $('result').hidden = false;
    $('checked-name').textContent = name;
    $('summary').textContent = summary.errors + ' error(s), ' + summary.warnings + ' warning(s), '
      + summary.infos + ' note(s)' + (file.problem ? ': ' + file.problem : '');
    const list = $('findings');
    list.replaceChildren();
    const codes = new Set();
    for (const f of file.findings) {
      codes.add(f.code);
      const source = checked.source[String(f.line)];
      list.append(canopener.el('li', {
        class: 'finding', 'data-code': f.code, 'data-severity': f.severity, 'data-line': f.line,
        'data-column': f.column,
      },
      canopener.el('div', {}, canopener.el('span', { class: 'sev' }, f.severity), ' ',
        canopener.el('b', { class: 'code' }, f.code), ' ',
        canopener.el('span', { class: 'where' }, name + ':' + f.line + ':' + f.column), ' ',
        canopener.el('span', { class: 'message' }, f.message)),
      source === undefined ? null : canopener.el('pre', {}, ...marked(source, f.column, f.length)),
      f.help ? canopener.el('div', { class: 'help' }, 'help: ' + f.help) : null));
    }
    const select = $('code');
    select.replaceChildren(canopener.el('option', { value: '' }, 'all codes'),
      ...[...codes].sort().map((c) => canopener.el('option', { value: c }, c)));
    const fixes = checked.fixes;
    $('fix-list').replaceChildren(...fixes.applied.map((f) => canopener.el('li', { 'data-code': f.code },
      f.code + ': ' + f.description + (f.changes_meaning ? ' (changes what the file says about the device)' : ''))));
    $('fix-summary').textContent = !fixes.available ? fixes.unavailable
      : fixes.applied.length === 0 ? 'No safe fix applies.'
        : fixes.applied.length + ' safe fix(es): errors ' + fixes.errors_before + ' → ' + fixes.errors_after + '.';
    const diff = $('diff');
    diff.replaceChildren(...fixes.diff.split('\n').map((line) => canopener.el('span', {
      class: line.startsWith('+') ? 'add' : line.startsWith('-') ? 'del' : line.startsWith('@@') ? 'hunk' : null,
    }, line + '\n')));
    diff.hidden = fixes.diff === '';
    $('download').hidden = !fixes.available || fixes.diff === '';
    filter();
  }

  // Sends `blob` under `name` (what the browser calls the file: shown, never a path on the server).
  page.upload = async function (name, blob) {
    page.file = { name, blob };
    page.report = null;
    page.refusal = null;
    const [ok, body] = await canopener.request('POST', '/api/check?name=' + encodeURIComponent(name), blob);
    if (ok) show(name, body); else refuse(body.error);
    return ok;
  };

  async function download() {
    const { name, blob } = page.file;
    const response = await fetch('/api/fix?name=' + encodeURIComponent(name), { method: 'POST', body: blob });
    if (!response.ok) { refuse((await response.json()).error); return; }
    const url = URL.createObjectURL(await response.blob());
    const link = canopener.el('a', { href: url, download: 'fixed-' + name });
    document.body.append(link);
    link.click();
    link.remove();
    URL.revokeObjectURL(url);
  }

  const drop = $('drop');
  drop.addEventListener('dragover', (e) => { e.preventDefault(); drop.classList.add('over'); });
  drop.addEventListener('dragleave', () => drop.classList.remove('over'));
  drop.addEventListener('drop', (e) => {
    e.preventDefault();
    drop.classList.remove('over');
    const file = e.dataTransfer.files[0];
    if (file) page.upload(file.name, file);
  });
  $('file').addEventListener('change', (e) => {
    const file = e.target.files[0];
    if (file) page.upload(file.name, file);
  });
  $('severities').addEventListener('change', filter);
  $('code').addEventListener('change', filter);
  $('download').addEventListener('click', download);
})();
