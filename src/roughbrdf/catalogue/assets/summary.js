(function () {
  "use strict";
  var D = JSON.parse(document.getElementById("rb-data").textContent);
  var cols = D.columns, n = D.links.length, size = D.pageSize;
  var data = cols.map(function (c, j) {
    var dict = D.dicts[c.key], col = D.data[j];
    return dict ? col.map(function (i) { return dict[i]; }) : col;
  });
  var statusCol = data[cols.findIndex(function (c) { return c.key === "status"; })];
  var view = [], page = 0, sortCol = -1, dir = 1, search = null;
  var collator = new Intl.Collator(undefined, {numeric: true, sensitivity: "base"});
  var thead = document.querySelector("#rb-table thead tr");
  var tbody = document.querySelector("#rb-table tbody");
  var info = document.getElementById("rb-info");
  var missing = function (v) { return v === null || v === undefined || v === ""; };

  function compare(a, b) {
    var x = data[sortCol][a], y = data[sortCol][b];
    if (missing(x)) { return missing(y) ? a - b : 1; }
    if (missing(y)) { return -1; }
    var c = cols[sortCol].type === "num" ? x - y : collator.compare(x, y);
    return c ? c * dir : a - b;
  }
  function applySort() { if (sortCol >= 0) { view.sort(compare); } }
  function applyFilter(q) {
    q = q.trim().toLowerCase();
    view = [];
    if (q && !search) {
      search = new Array(n);
      for (var i = 0; i < n; i++) {
        search[i] = data.map(function (col) { return missing(col[i]) ? "" : col[i]; })
          .join(" ").toLowerCase();
      }
    }
    for (var k = 0; k < n; k++) { if (!q || search[k].indexOf(q) >= 0) { view.push(k); } }
    applySort();
    page = 0;
  }
  function fmt(v, type) {
    if (missing(v)) { return ""; }
    if (type === "num" && !Number.isInteger(v)) {
      var a = Math.abs(v);
      return a && (a < 1e-3 || a >= 1e6) ? v.toExponential(3) : Number(v.toPrecision(4)).toString();
    }
    return String(v);
  }
  function render() {
    var pages = Math.max(1, Math.ceil(view.length / size));
    page = Math.min(Math.max(page, 0), pages - 1);
    var start = page * size, stop = Math.min(view.length, start + size);
    var frag = document.createDocumentFragment();
    for (var i = start; i < stop; i++) {
      var r = view[i], tr = document.createElement("tr");
      tr.className = "st-" + String(statusCol[r]).split(" ")[0].replace("not", "not-converged");
      cols.forEach(function (c, j) {
        var td = document.createElement("td"), v = data[j][r];
        td.className = c.type === "num" ? "num" : (c.key === "error" ? "err" : "");
        if (c.key === "file" && D.links[r]) {
          var a = document.createElement("a");
          a.href = D.links[r]; a.textContent = fmt(v, c.type); td.appendChild(a);
        } else { td.textContent = fmt(v, c.type); }
        tr.appendChild(td);
      });
      frag.appendChild(tr);
    }
    tbody.textContent = "";
    tbody.appendChild(frag);
    info.textContent = view.length ? "rows " + (start + 1) + "\u2013" + stop + " of " +
      view.length + " (page " + (page + 1) + " of " + pages + ")" : "no rows";
    document.getElementById("rb-prev").disabled = page === 0;
    document.getElementById("rb-next").disabled = page >= pages - 1;
  }
  cols.forEach(function (c, j) {
    var th = document.createElement("th");
    th.textContent = c.label; th.dataset.key = c.key; th.title = "sort by " + c.label;
    th.addEventListener("click", function () {
      if (sortCol === j) { dir = -dir; } else { sortCol = j; dir = 1; }
      Array.prototype.forEach.call(thead.children, function (h) {
        h.removeAttribute("aria-sort");
      });
      th.setAttribute("aria-sort", dir > 0 ? "ascending" : "descending");
      applySort(); page = 0; render();
    });
    thead.appendChild(th);
  });
  document.getElementById("rb-prev").addEventListener("click", function () { page--; render(); });
  document.getElementById("rb-next").addEventListener("click", function () { page++; render(); });
  document.getElementById("rb-filter").addEventListener("input", function (e) {
    applyFilter(e.target.value); render();
  });
  applyFilter("");
  render();
  document.body.dataset.ready = "1";
})();
