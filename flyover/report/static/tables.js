/* flyover dataset browser: click a column head of a data table to sort by it (again: reverse).
   Plain JavaScript; numbers sort as numbers ("—" last), text as text. */
(function () {
  "use strict";
  function key(cell) {
    var t = cell.textContent.trim();
    if (t === "—" || t === "") { return { n: Infinity, t: "" }; }
    var n = Number(t.replace(/[ ,%]/g, "").replace("∞", "Infinity").split("/")[0]);
    return { n: isNaN(n) ? null : n, t: t.toLowerCase() };
  }
  document.querySelectorAll("table.data").forEach(function (table) {
    var body = table.tBodies[0];
    if (!table.tHead || !body) { return; }
    Array.prototype.forEach.call(table.tHead.rows[0].cells, function (th, col) {
      th.classList.add("sortable");
      th.title = "sort by " + th.textContent;
      th.addEventListener("click", function () {
        var dir = th.getAttribute("aria-sort") === "ascending" ? -1 : 1;
        Array.prototype.forEach.call(table.tHead.rows[0].cells, function (o) { o.removeAttribute("aria-sort"); });
        th.setAttribute("aria-sort", dir === 1 ? "ascending" : "descending");
        var rows = Array.prototype.slice.call(body.rows);
        rows.sort(function (a, b) {
          var x = key(a.cells[col] || a.cells[0]), y = key(b.cells[col] || b.cells[0]);
          if (x.n !== null && y.n !== null && x.n !== y.n) { return dir * (x.n < y.n ? -1 : 1); }
          return dir * x.t.localeCompare(y.t);
        });
        rows.forEach(function (r) { body.appendChild(r); });
      });
    });
  });
}());
