/* emaphm fleet health site: sort, filter and page the index table. No dependencies, no
   network; reads the rows from the inline JSON block #fleet-data, each with its table row
   as HTML (every value in it escaped when the site was built). The page itself holds the
   first rows in the order of attention, so it reads without this script; with it, the
   whole fleet is sorted and filtered here and shown a page (page_rows) at a time. */
(function () {
  "use strict";
  var dataEl = document.getElementById("fleet-data");
  var table = document.getElementById("fleet");
  if (!dataEl || !table) { return; }
  var data = JSON.parse(dataEl.textContent);
  var rowsData = data.actuators;
  var pageRows = data.page_rows > 0 ? data.page_rows : Math.max(rowsData.length, 1);
  var tbody = table.tBodies[0];
  var filterEl = document.getElementById("filter");
  var showEl = document.getElementById("show");
  var sortEl = document.getElementById("sort");
  var shownEl = document.getElementById("shown");
  var emptyEl = document.getElementById("empty");
  var pagerEl = document.getElementById("pager");
  var pageEl = document.getElementById("page");
  var prevEl = document.getElementById("prev");
  var nextEl = document.getElementById("next");
  var collator = window.Intl && Intl.Collator ? new Intl.Collator() : null;
  var state = { key: "rank", dir: 1, page: 0 };
  var order = null;          // row indices in the current sort, kept until the sort changes

  function compareText(u, v) { return collator ? collator.compare(u, v) : u.localeCompare(v); }

  function compare(i, j) {
    var x = rowsData[i], y = rowsData[j];
    var u = x.sort[state.key], v = y.sort[state.key];
    if (u !== v) {
      if (u === null || u === undefined) { return 1; }      // missing values last, both ways
      if (v === null || v === undefined) { return -1; }
      if (typeof u === "string") {
        var c = compareText(u, v);
        if (c) { return state.dir * c; }
      } else {
        return state.dir * (u < v ? -1 : 1);
      }
    }
    return x.rank - y.rank;
  }

  function sorted() {
    if (order === null) {
      order = [];
      for (var i = 0; i < rowsData.length; i++) { order.push(i); }
      order.sort(compare);
    }
    return order;
  }

  function matches(d, words, show) {
    if (show && d.tags.indexOf(show) < 0) { return false; }
    for (var i = 0; i < words.length; i++) {
      if (d.text.indexOf(words[i]) < 0) { return false; }
    }
    return true;
  }

  function apply() {
    var words = (filterEl ? filterEl.value : "").toLowerCase().split(/\s+/).filter(Boolean);
    var show = showEl ? showEl.value : "";
    var shown = sorted().filter(function (i) { return matches(rowsData[i], words, show); });
    var n = shown.length;
    var pages = Math.max(1, Math.ceil(n / pageRows));
    state.page = Math.min(Math.max(state.page, 0), pages - 1);
    var first = state.page * pageRows;
    var html = [];
    shown.slice(first, first + pageRows).forEach(function (i) { html.push(rowsData[i].html); });
    tbody.innerHTML = html.join("");
    if (shownEl) { shownEl.textContent = n + " of " + rowsData.length + " shown"; }
    if (emptyEl) { emptyEl.hidden = n > 0; }
    if (pagerEl) {
      pagerEl.hidden = pages < 2;
      pageEl.textContent = "page " + (state.page + 1) + " of " + pages + " (" + (first + 1) +
        "\u2013" + Math.min(first + pageRows, n) + ")";
      prevEl.disabled = state.page === 0;
      nextEl.disabled = state.page >= pages - 1;
    }
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

  function resort(key, dir) {
    state.key = key;
    state.dir = dir;
    state.page = 0;
    order = null;
    apply();
  }

  function refilter() {
    state.page = 0;
    apply();
  }

  Array.prototype.forEach.call(table.tHead.querySelectorAll("button[data-key]"), function (b) {
    b.addEventListener("click", function () {
      var key = b.getAttribute("data-key");
      resort(key, key === state.key ? -state.dir : 1);
    });
  });
  if (sortEl) { sortEl.addEventListener("change", function () { resort(sortEl.value, 1); }); }
  if (filterEl) { filterEl.addEventListener("input", refilter); }
  if (showEl) { showEl.addEventListener("change", refilter); }
  if (prevEl) { prevEl.addEventListener("click", function () { state.page -= 1; apply(); }); }
  if (nextEl) { nextEl.addEventListener("click", function () { state.page += 1; apply(); }); }
  var form = document.getElementById("controls");
  if (form) { form.addEventListener("submit", function (e) { e.preventDefault(); }); }
  document.documentElement.className += " js";
  apply();
}());
