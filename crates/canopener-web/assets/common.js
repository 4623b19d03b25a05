// canopener serve: helpers every page's script shares. Plain JavaScript, no build step.
'use strict';
const canopener = window.canopener || (window.canopener = {});

canopener.el = function (tag, attrs, ...children) {
  const node = document.createElement(tag);
  for (const [key, value] of Object.entries(attrs || {})) {
    if (value === null || value === undefined) continue;
    if (key === 'class') node.className = value; else node.setAttribute(key, value);
  }
  for (const child of children) {
    if (child === null || child === undefined) continue;
    node.append(child instanceof Node ? child : String(child));
  }
  return node;
};

// A JSON request; resolves to [ok, body], where a refused request's body is {error}.
canopener.request = async function (method, url, body, headers) {
  const response = await fetch(url, { method, body, headers: headers || {} });
  const type = response.headers.get('content-type') || '';
  const data = type.includes('json') ? await response.json() : { error: await response.text() };
  return [response.ok, data, response.status];
};
