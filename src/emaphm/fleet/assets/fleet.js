/* emaphm fleet health site: sort and filter the index table. No dependencies, no network;
   reads the rows from the inline JSON block #fleet-data (the table itself is complete
   without this script, in attention order). */
(function () {
  "use strict";
  var dataEl = document.getElementById("fleet-data");
  var table = document.getElementById("fleet");
  if (!dataEl || !table) { return; }
  var rowsData = JSON.parse(dataEl.textContent).actuators;
  var tbody = table.tBodies[0];
  var rows = Array.prototype.slice.call(tbody.rows);
  var filterEl = document.getElementById("filter");
  var showEl = document.getElementById("show");
  var sortEl = document.getElementById("sort");
  var shownEl = document.getElementById("shown");
  var emptyEl = document.getElementById("empty");
  var state = { key: "rank", dir: 1 };

  function datum(row) { return rowsData[Number(row.getAttribute("data-i"))]; }

  function compare(a, b) {
    var x = datum(a), y = datum(b);
    var u = x.sort[state.key], v = y.sort[state.key];
    if (u !== v) {
      if (u === null || u === undefined) { return 1; }      // missing values last, both ways
      if (v === null || v === undefined) { return -1; }
      if (typeof u === "string") { return state.dir * u.localeCompare(v); }
      return state.dir * (u < v ? -1 : 1);
    }
    return x.rank - y.rank;
  }

  function matches(d, words, show) {
    if (show && d.tags.indexOf(show) < 0) { return false; }
    for (var i = 0; i < words.length; i++) {
      if (d.text.indexOf(words[i]) < 0) { return false; }
    }
    return true;
  }

  function apply() {
    var sorted = rows.slice().sort(compare);
    sorted.forEach(function (row) { tbody.appendChild(row); });
    var words = (filterEl ? filterEl.value : "").toLowerCase().split(/\s+/).filter(Boolean);
    var show = showEl ? showEl.value : "";
    var n = 0;
    rows.forEach(function (row) {
      var ok = matches(datum(row), words, show);
      row.hidden = !ok;
      if (ok) { n += 1; }
    });
    if (shownEl) { shownEl.textContent = n + " of " + rows.length + " shown"; }
    if (emptyEl) { emptyEl.hidden = n > 0; }
    Array.prototype.forEach.call(table.tHead.rows[0].cells, function (th) {
      var key = th.getAttribute("data-key");
      if (key === state.key) {
        th.setAttribute("aria-sort", state.dir > 0 ? "ascending" : "descending");
      } else {
        th.removeAttribute("aria-sort");
      }
    });
    if (sortEl && sortEl.value !== state.key) { sortEl.value = state.key; }
  }

  Array.prototype.forEach.call(table.tHead.querySelectorAll("button[data-key]"), function (b) {
    b.addEventListener("click", function () {
      var key = b.getAttribute("data-key");
      state.dir = key === state.key ? -state.dir : 1;
      state.key = key;
      apply();
    });
  });
  if (sortEl) {
    sortEl.addEventListener("change", function () {
      state.key = sortEl.value;
      state.dir = 1;
      apply();
    });
  }
  if (filterEl) { filterEl.addEventListener("input", apply); }
  if (showEl) { showEl.addEventListener("change", apply); }
  var form = document.getElementById("controls");
  if (form) { form.addEventListener("submit", function (e) { e.preventDefault(); }); }
  document.documentElement.className += " js";
  apply();
}());
