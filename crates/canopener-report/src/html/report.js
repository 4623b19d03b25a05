// Filters for the canopener check report. State lives in the URL hash
// (#severity=error,warning&code=C301) so a filtered view can be shared and tested headlessly.
(function () {
  'use strict';
  var form = document.getElementById('filters');
  var boxes = Array.prototype.slice.call(document.querySelectorAll('input[name="severity"]'));
  var select = document.getElementById('code-filter');
  var findings = Array.prototype.slice.call(document.querySelectorAll('.finding'));
  var files = Array.prototype.slice.call(document.querySelectorAll('section.file'));
  var rows = Array.prototype.slice.call(document.querySelectorAll('#by-code tbody tr'));
  var shown = document.getElementById('shown-count');
  var none = document.getElementById('no-match');
  if (!form || !select) { return; }

  function hasOption(code) {
    for (var i = 0; i < select.options.length; i++) {
      if (select.options[i].value === code) { return true; }
    }
    return false;
  }

  function selected() {
    var set = {};
    boxes.forEach(function (b) { if (b.checked) { set[b.value] = true; } });
    return set;
  }

  function apply() {
    var severities = selected();
    var code = select.value;
    var count = 0;
    findings.forEach(function (el) {
      var ok = severities[el.getAttribute('data-severity')] === true &&
        (code === '' || el.getAttribute('data-code') === code);
      el.hidden = !ok;
      if (ok) { count++; }
    });
    var anyFile = false;
    files.forEach(function (file) {
      var problem = file.querySelector('.problem');
      var problemShown = problem !== null && severities.error === true && code === '';
      if (problem !== null) { problem.hidden = !problemShown; }
      file.hidden = !(problemShown || file.querySelector('.finding:not([hidden])') !== null);
      if (!file.hidden) { anyFile = true; }
    });
    rows.forEach(function (row) {
      var ok = severities[row.getAttribute('data-severity')] === true &&
        (code === '' || row.getAttribute('data-code') === code);
      row.classList.toggle('dim', !ok);
    });
    if (shown) { shown.textContent = String(count); }
    if (none) { none.hidden = anyFile || findings.length === 0; }
  }

  // Reads filters from the hash; false when the hash is not a filter (e.g. #check-C301).
  function readHash() {
    var raw = location.hash.replace(/^#/, '');
    if (raw.indexOf('=') < 0) { return false; }
    var params = new URLSearchParams(raw);
    var severity = params.get('severity');
    var wanted = null;
    if (severity !== null && severity.trim() !== '') {
      wanted = {};
      severity.split(',').forEach(function (s) { wanted[s.trim().toLowerCase()] = true; });
    }
    boxes.forEach(function (b) { b.checked = wanted === null || wanted[b.value] === true; });
    var code = params.get('code');
    if (code !== null && code !== '' && !hasOption(code)) {
      // A code without findings in this report: selectable, and shows nothing.
      select.add(new Option(code + ' (0)', code));
    }
    select.value = code === null ? '' : code;
    return true;
  }

  function writeHash() {
    var parts = [];
    var checked = boxes.filter(function (b) { return b.checked; }).map(function (b) { return b.value; });
    if (checked.length !== boxes.length) {
      parts.push('severity=' + (checked.length === 0 ? 'none' : checked.join(',')));
    }
    if (select.value !== '') { parts.push('code=' + encodeURIComponent(select.value)); }
    var url = location.pathname + location.search + (parts.length > 0 ? '#' + parts.join('&') : '');
    try { history.replaceState(null, '', url); } catch (e) { /* some file:// contexts refuse */ }
  }

  // Opens the explanation a #check-CODE link points at.
  function openTarget() {
    var raw = location.hash.replace(/^#/, '');
    if (raw.indexOf('check-') !== 0) { return; }
    var el = document.getElementById(raw);
    if (el === null) {
      try { el = document.getElementById(decodeURIComponent(raw)); } catch (e) { el = null; }
    }
    if (el !== null && el.tagName === 'DETAILS') {
      el.open = true;
      el.scrollIntoView();
    }
  }

  boxes.forEach(function (b) { b.addEventListener('change', function () { apply(); writeHash(); }); });
  select.addEventListener('change', function () { apply(); writeHash(); });
  document.getElementById('reset-filters').addEventListener('click', function () {
    boxes.forEach(function (b) { b.checked = true; });
    select.value = '';
    apply();
    writeHash();
  });
  window.addEventListener('hashchange', function () {
    if (readHash()) {
      apply();
      // A filter link (a count in the per-code table) was followed: show its result.
      form.scrollIntoView();
    } else {
      openTarget();
    }
  });

  form.hidden = false;
  readHash();
  apply();
  openTarget();
  document.body.setAttribute('data-ready', 'true');
}());
