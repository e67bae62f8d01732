// Injected at the top of a copy of a report by tests/report_browser.rs; runs in headless
// Chromium and writes what a reader would object to into <pre id="mtec-check"> as JSON.
// Checks: script errors, empty plots, text over data points of a plot, content wider than its
// box (text overflow), and a page wider than the window.
(function () {
  var errors = [];
  window.addEventListener("error", function (e) { errors.push(String(e.message)); });
  var origError = console.error;
  console.error = function () {
    errors.push(Array.prototype.join.call(arguments, " "));
    origError.apply(console, arguments);
  };

  // the vertices of a plot's data marks, in page pixels (rotated labels and a scaled svg
  // included); long segments are sampled every 2 units so that a line crossing a label is found
  // even between its vertices
  function dataPoints(svg) {
    var user = dataPointsUser(svg);
    var m = svg.getScreenCTM();
    var p = svg.createSVGPoint();
    return user.map(function (u) {
      p.x = u[0]; p.y = u[1];
      var q = p.matrixTransform(m);
      return [q.x, q.y];
    });
  }

  function dataPointsUser(svg) {
    var pts = [];
    svg.querySelectorAll("polyline").forEach(function (pl) {
      var p = pl.points;
      if (p.numberOfItems < 3) return; // ticks, spokes, legend samples
      for (var i = 0; i < p.numberOfItems; i++) {
        var a = p.getItem(i);
        pts.push([a.x, a.y]);
        if (i + 1 < p.numberOfItems) {
          var b = p.getItem(i + 1);
          var n = Math.floor(Math.hypot(b.x - a.x, b.y - a.y) / 2);
          for (var k = 1; k < n; k++) {
            pts.push([a.x + (b.x - a.x) * k / n, a.y + (b.y - a.y) * k / n]);
          }
        }
      }
    });
    svg.querySelectorAll("circle").forEach(function (c) {
      pts.push([c.cx.baseVal.value, c.cy.baseVal.value]);
    });
    return pts;
  }

  function dataMarks(svg) {
    var n = 0;
    svg.querySelectorAll("polyline").forEach(function (pl) { if (pl.points.numberOfItems >= 3) n++; });
    n += svg.querySelectorAll("circle, polygon").length;
    var w = svg.viewBox && svg.viewBox.baseVal ? svg.viewBox.baseVal.width : 0;
    svg.querySelectorAll("rect").forEach(function (r) {
      if (r.width.baseVal.value < 0.9 * (w || svg.width.baseVal.value)) n++;
    });
    return n;
  }

  window.addEventListener("load", function () {
    var problems = [];
    var figures = document.querySelectorAll("figure.plot");
    figures.forEach(function (fig, i) {
      var cap = (fig.querySelector("figcaption") || {}).textContent || "";
      var where = "figure " + (i + 1) + " (" + cap.slice(0, 60) + ")";
      var svg = fig.querySelector("svg");
      if (!svg) { problems.push(where + ": no svg"); return; }
      var box = svg.getBoundingClientRect();
      if (box.width < 50 || box.height < 50) problems.push(where + ": drawn " + box.width + "×" + box.height + " px");
      if (dataMarks(svg) === 0) problems.push(where + ": empty plot (no data marks)");
      if (cap.trim().length < 20) problems.push(where + ": caption too short to say what to look at");
      var pts = dataPoints(svg);
      svg.querySelectorAll("text").forEach(function (t) {
        var b = t.getBoundingClientRect();
        if (b.width === 0 || !t.textContent.trim()) return;
        var inside = 0;
        for (var k = 0; k < pts.length; k++) {
          var x = pts[k][0], y = pts[k][1];
          if (x > b.x + 1 && x < b.x + b.width - 1 && y > b.y + 1 && y < b.y + b.height - 1) inside++;
        }
        if (inside > 0) problems.push(where + ": text \"" + t.textContent.slice(0, 40) + "\" covers " + inside + " data point(s)");
      });
      if (svg.querySelectorAll("text").length < 3) problems.push(where + ": no axis labels");
      // labels over labels (e.g. category names too long for their bars)
      var boxes = [];
      svg.querySelectorAll("text").forEach(function (t) {
        var b = t.getBoundingClientRect();
        if (b.width > 0 && t.textContent.trim()) boxes.push([b, t.textContent.trim()]);
      });
      for (var a = 0; a < boxes.length; a++) {
        for (var c = a + 1; c < boxes.length; c++) {
          var p = boxes[a][0], q = boxes[c][0];
          var w = Math.min(p.x + p.width, q.x + q.width) - Math.max(p.x, q.x);
          var h = Math.min(p.y + p.height, q.y + q.height) - Math.max(p.y, q.y);
          if (w > 1 && h > 1 && w * h > 0.2 * Math.min(p.width * p.height, q.width * q.height)) {
            problems.push(where + ": labels \"" + boxes[a][1].slice(0, 30) + "\" and \"" + boxes[c][1].slice(0, 30) + "\" overlap");
          }
        }
      }
    });
    document.querySelectorAll("td, th, p, figcaption, h1, h2").forEach(function (el) {
      if (el.scrollWidth > el.clientWidth + 1 && getComputedStyle(el).overflow !== "visible") {
        problems.push("text overflows its box: " + el.textContent.slice(0, 60));
      }
    });
    document.querySelectorAll("table, figure").forEach(function (el) {
      var r = el.getBoundingClientRect();
      var body = document.body.getBoundingClientRect();
      if (r.right > body.right + 2) problems.push(el.tagName.toLowerCase() + " wider than the page: " + el.textContent.slice(0, 60));
    });
    if (document.documentElement.scrollWidth > window.innerWidth + 1) {
      problems.push("the page scrolls sideways: " + document.documentElement.scrollWidth + " px in a " + window.innerWidth + " px window");
    }
    var out = document.createElement("pre");
    out.id = "mtec-check";
    out.textContent = JSON.stringify({ figures: figures.length, errors: errors, problems: problems });
    document.body.appendChild(out);
  });
})();
