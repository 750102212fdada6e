/* flyover dataset browser: pan, zoom and hover of an interchange's plan view.
   Plain JavaScript, no library, no network: the SVG is in the page, the facts of each
   road and ramp are in <script type="application/json" id="view-info">. */
(function () {
  "use strict";
  var viewer = document.getElementById("viewer");
  var svg = document.getElementById("plan");
  var tip = document.getElementById("tip");
  if (!viewer || !svg || !tip) { return; }
  var info = JSON.parse(document.getElementById("view-info").textContent);
  var home = svg.getAttribute("viewBox").split(/\s+/).map(Number);
  var box = home.slice();
  var ramps = Array.prototype.slice.call(svg.querySelectorAll("polyline.ramp"));

  function setBox(b) {
    box = b;
    svg.setAttribute("viewBox", b.map(function (v) { return v.toFixed(2); }).join(" "));
    // labels keep about 12 px on screen at any zoom
    var scale = Math.max(b[2] / Math.max(svg.clientWidth, 1), b[3] / Math.max(svg.clientHeight, 1));
    svg.querySelectorAll(".labels text").forEach(function (t) {
      t.style.fontSize = (12 * scale).toFixed(2) + "px";
      t.style.strokeWidth = (3 * scale).toFixed(2) + "px";
    });
    // a ramp is as wide as its lanes, but never thinner than 2.5 px on screen
    var least = 2.5 * scale;
    ramps.forEach(function (p) {
      p.setAttribute("stroke-width", Math.max(Number(p.getAttribute("data-w")), least).toFixed(2));
    });
  }

  function toView(clientX, clientY) {
    var m = svg.getScreenCTM();
    if (!m) { return { x: 0, y: 0 }; }
    var p = svg.createSVGPoint();
    p.x = clientX; p.y = clientY;
    var q = p.matrixTransform(m.inverse());
    return { x: q.x, y: q.y };
  }

  function zoom(factor, clientX, clientY) {
    var r = svg.getBoundingClientRect();
    if (clientX === undefined) { clientX = r.left + r.width / 2; clientY = r.top + r.height / 2; }
    var c = toView(clientX, clientY);
    var w = Math.min(Math.max(box[2] * factor, home[2] / 200), home[2] * 8);
    var f = w / box[2];
    setBox([c.x - (c.x - box[0]) * f, c.y - (c.y - box[1]) * f, box[2] * f, box[3] * f]);
  }

  viewer.addEventListener("wheel", function (e) {
    e.preventDefault();
    zoom(Math.pow(1.0015, e.deltaY), e.clientX, e.clientY);
  }, { passive: false });

  var drag = null;
  viewer.addEventListener("pointerdown", function (e) {
    if (e.button !== 0 || e.target.closest(".controls")) { return; }
    drag = { x: e.clientX, y: e.clientY, box: box.slice() };
    viewer.setPointerCapture(e.pointerId);
    viewer.classList.add("dragging");
  });
  viewer.addEventListener("pointermove", function (e) {
    if (drag) {
      var a = toView(drag.x, drag.y), b = toView(e.clientX, e.clientY);
      setBox([box[0] - (b.x - a.x), box[1] - (b.y - a.y), box[2], box[3]]);
      drag.x = e.clientX; drag.y = e.clientY;
      return;
    }
    var el = e.target.closest ? e.target.closest("[data-el]") : null;
    if (el) { show(el.getAttribute("data-el"), e.clientX, e.clientY); } else { hide(); }
  });
  function endDrag(e) {
    if (!drag) { return; }
    drag = null;
    viewer.classList.remove("dragging");
    try { viewer.releasePointerCapture(e.pointerId); } catch (err) { /* already released */ }
  }
  viewer.addEventListener("pointerup", endDrag);
  viewer.addEventListener("pointercancel", endDrag);
  viewer.addEventListener("pointerleave", function () { if (!drag) { hide(); } });

  viewer.addEventListener("keydown", function (e) {
    if (e.key === "+" || e.key === "=") { zoom(1 / 1.3); }
    else if (e.key === "-") { zoom(1.3); }
    else if (e.key === "0") { setBox(home.slice()); }
    else { return; }
    e.preventDefault();
  });
  viewer.querySelectorAll(".controls button").forEach(function (b) {
    b.addEventListener("click", function () {
      var z = b.getAttribute("data-zoom");
      if (z === "in") { zoom(1 / 1.3); } else if (z === "out") { zoom(1.3); } else { setBox(home.slice()); }
    });
  });

  function num(v, digits) {
    if (v === null || v === undefined) { return "—"; }
    if (v === "inf") { return "∞"; }
    if (typeof v !== "number") { return String(v); }
    return v.toFixed(digits);
  }
  function row(table, key, value) {
    var tr = table.insertRow();
    var k = tr.insertCell(); k.className = "k"; k.textContent = key;
    tr.insertCell().textContent = value;
  }

  var active = null;
  function highlight(name, on) {
    svg.querySelectorAll('[data-el="' + CSS.escape(name) + '"]').forEach(function (n) {
      n.classList.toggle("active", on);
    });
    document.querySelectorAll('#ramps tr[data-el="' + CSS.escape(name) + '"]').forEach(function (n) {
      n.classList.toggle("hover", on);
    });
  }

  function show(name, clientX, clientY) {
    var f = info[name];
    if (!f) { hide(); return; }
    if (active !== name) {
      if (active) { highlight(active, false); }
      active = name;
      highlight(name, true);
      tip.textContent = "";
      var title = document.createElement("b");
      title.textContent = (f.kind === "ramp" ? "ramp " : "road ") + f.name;
      tip.appendChild(title);
      var t = document.createElement("table");
      if (f.kind === "ramp") {
        row(t, "from → to", f.from + " → " + f.to);
        row(t, "lanes", String(f.lanes));
        row(t, "radius", "target " + num(f.target_radius_m, 0) + " m, achieved " + num(f.min_radius_m, 1) + " m");
        row(t, "slope", "target " + num(f.target_slope_pct, 1) + " %, achieved " + num(f.max_slope_pct, 2) + " %");
        row(t, "length", num(f.length_m, 0) + " m");
        row(t, "height", num(f.height_m[0], 1) + " – " + num(f.height_m[1], 1) + " m");
        row(t, "targets", f.ok ? "met" : "missed" + (f.infeasible ? ": " + f.infeasible : ""));
        if (f.fuel_ml !== undefined) {
          row(t, "truck fuel", f.fuel_completed ?
            num(f.fuel_ml, 0) + " ml, " + num(f.fuel_ml_per_km, 0) + " ml/km (" + f.fuel_direction + ")" :
            "not completed");
        }
      } else {
        row(t, "expressway", f.expressway);
        row(t, "lanes", String(f.lanes));
        row(t, "height", num(f.height_m, 1) + " m");
        row(t, "length", num(f.length_m, 0) + " m");
      }
      tip.appendChild(t);
      tip.hidden = false;
    }
    var r = viewer.getBoundingClientRect();
    var x = clientX - r.left + 14, y = clientY - r.top + 14;
    if (x + tip.offsetWidth > r.width) { x = Math.max(0, clientX - r.left - tip.offsetWidth - 14); }
    if (y + tip.offsetHeight > r.height) { y = Math.max(0, clientY - r.top - tip.offsetHeight - 14); }
    tip.style.left = x + "px";
    tip.style.top = y + "px";
  }
  function hide() {
    if (active) { highlight(active, false); }
    active = null;
    tip.hidden = true;
  }

  // a row of the ramp table shows its ramp in the view
  document.querySelectorAll("#ramps tr[data-el]").forEach(function (tr) {
    tr.addEventListener("mouseenter", function () {
      var name = tr.getAttribute("data-el");
      var hit = svg.querySelector('.hits [data-el="' + CSS.escape(name) + '"]');
      if (!hit) { return; }
      var b = hit.getBoundingClientRect(), r = viewer.getBoundingClientRect();
      show(name, Math.min(Math.max(b.left + b.width / 2, r.left), r.right),
           Math.min(Math.max(b.top + b.height / 2, r.top), r.bottom));
    });
    tr.addEventListener("mouseleave", hide);
  });

  window.addEventListener("resize", function () { setBox(box); });
  setBox(home.slice());
  viewer.setAttribute("data-ready", "1");
}());
