"""The web page in a real browser, against a real ``certsolve serve`` (slow, opt-in).

Headless Chromium from the distribution's packages (``apt-get install chromium
chromium-driver``) driven by selenium, never a downloaded browser.  The page is used as a
person would: FK jobs (planar, and spatial in 3-D) submitted through the form until their
pose pictures and tensions show, a map through its form, a long solve watched and cancelled
from its page, a job cancelled from the list, and bad input -- a malformed robot file, a
control vector of the wrong length, a file that is not JSON -- answered beside the field
with the API's message.

    pytest -m slow tests/test_web_browser.py
    CERTSOLVE_SCREENSHOTS=docs pytest -m slow tests/test_web_browser.py   # and the pictures

Skips, saying why, when chromium, chromedriver or selenium is missing.
"""

import json
import os
import re
import shutil
import tempfile
import time
from pathlib import Path

import numpy as np
import pytest
from test_service_e2e import Server, hard_system

pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[1]
PLANAR = json.loads((ROOT / "examples/robots/planar.json").read_text())
FLAGS = (
    "--headless --no-sandbox --disable-gpu --disable-quic --no-first-run "
    "--disable-background-networking --disable-component-update --disable-sync "
    "--window-size=1280,1000"
).split()
SHOTS = os.environ.get("CERTSOLVE_SCREENSHOTS")  # a folder: write the README's screenshots


def _browser_paths() -> tuple[str, str]:
    chromium = next(
        (p for p in map(shutil.which, ("chromium", "chromium-browser", "google-chrome")) if p),
        None,
    )
    driver = shutil.which("chromedriver")
    if chromium is None or driver is None:
        pytest.skip(
            "no headless browser: install Debian's chromium and chromium-driver "
            "(apt-get install -y chromium chromium-driver)"
        )
    return chromium, driver


def _chromium(*flags: str):
    """Headless Chromium driven by selenium (a generator: the driver, then clean-up), with
    ``flags`` beside :data:`FLAGS` and the console log kept."""
    chromium, driver_path = _browser_paths()
    try:
        from selenium import webdriver
        from selenium.webdriver.chrome.service import Service
    except ImportError:
        pytest.skip("selenium is not installed (pip install -e '.[dev]')")
    os.environ["SE_OFFLINE"] = "true"  # selenium must not fetch a browser or a driver
    options = webdriver.ChromeOptions()
    options.binary_location = chromium
    for flag in (*FLAGS, *flags):
        options.add_argument(flag)
    options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    profile = tempfile.mkdtemp(prefix="certsolve-chromium-")
    options.add_argument(f"--user-data-dir={profile}")
    driver = webdriver.Chrome(service=Service(driver_path), options=options)
    yield driver
    driver.quit()
    shutil.rmtree(profile, ignore_errors=True)


@pytest.fixture(scope="module")
def browser():
    yield from _chromium()


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    s = Server(tmp_path_factory.mktemp("web") / "data", 2)
    yield s
    s.close()


# -- helpers ---------------------------------------------------------------------------------------
def wait(driver, condition, timeout=60.0, what="condition"):
    from selenium.common.exceptions import StaleElementReferenceException
    from selenium.webdriver.support.ui import WebDriverWait

    WebDriverWait(driver, timeout, ignored_exceptions=(StaleElementReferenceException,)).until(
        lambda d: condition(d), message=f"timed out waiting for {what}"
    )


def css(driver, selector):
    from selenium.webdriver.common.by import By

    return driver.find_element(By.CSS_SELECTOR, selector)


def css_all(driver, selector):
    from selenium.webdriver.common.by import By

    return driver.find_elements(By.CSS_SELECTOR, selector)


def open_home(driver, server, tab="fk"):
    driver.get(server.base + "/#/")
    driver.refresh()  # a fresh page: forms as first built
    wait(driver, lambda d: css_all(d, "#form-fk select[name=robot] option[value=planar]"), 30,
         "the bundled robots")  # fmt: skip
    css(driver, f'#tabs button[data-kind="{tab}"]').click()
    return css(driver, f"#form-{tab}")


def fill(form, name, text):
    from selenium.webdriver.common.by import By

    box = form.find_element(By.CSS_SELECTOR, f'[name="{name}"]')
    box.clear()
    box.send_keys(text)


def choose_robot(form, value):
    from selenium.webdriver.common.by import By
    from selenium.webdriver.support.ui import Select

    Select(form.find_element(By.CSS_SELECTOR, "select[name=robot]")).select_by_value(value)


def submit_form(driver, form) -> str:
    """Submit and wait for the job page; returns the job id."""
    from selenium.webdriver.common.by import By

    form.find_element(By.CSS_SELECTOR, "button[type=submit]").click()
    wait(driver, lambda d: re.search(r"#/jobs/\w+$", d.current_url), 30, "the job page")
    return driver.current_url.rsplit("/", 1)[1]


def pictures_loaded(driver, selector) -> int:
    """How many pictures under ``selector`` are loaded (0 while any is still missing)."""
    return driver.execute_script(
        "const imgs = [...document.querySelectorAll(arguments[0])];"
        "return imgs.length && imgs.every(i => i.complete && i.naturalWidth > 0)"
        " ? imgs.length : 0;",
        selector,
    )


def screenshot(driver, name):
    """The whole page, into $CERTSOLVE_SCREENSHOTS/<name> (when set)."""
    if not SHOTS:
        return
    height = driver.execute_script("return document.documentElement.scrollHeight")
    driver.set_window_size(1280, min(max(height + 120, 700), 4000))  # + the window frame
    driver.execute_script("window.scrollTo(0, 0)")
    time.sleep(0.3)
    Path(SHOTS).mkdir(parents=True, exist_ok=True)
    driver.save_screenshot(str(Path(SHOTS) / name))
    driver.set_window_size(1280, 1000)


def api_message(server, body, field) -> str:
    """The API's own words for ``field`` in the 422 answer to ``body``."""
    r = server.http.post("/v1/jobs", json=body)
    assert r.status_code == 422, r.text
    (d,) = [d for d in r.json()["detail"] if d["field"] == field]
    return f"{d['field']}: {d['msg']}"


def field_error(form, field) -> str:
    from selenium.webdriver.common.by import By

    return form.find_element(
        By.CSS_SELECTOR, f'.field[data-field="{field}"] .field-error'
    ).text.strip()


# -- the tests -------------------------------------------------------------------------------------
def test_fk_job_from_the_form_shows_poses_and_tensions(browser, server):
    form = open_home(browser, server, "fk")
    choose_robot(form, "planar")
    fill(form, "params.u", "0.8, 1.8, -2.5, -3.6")
    fill(form, "params.tau_max", "60")
    job_id = submit_form(browser, form)
    wait(browser, lambda d: css_all(d, "#verdict"), 180, "the FK job to finish")
    result = server.job(job_id)["result"]
    poses = result["solutions"]
    assert result["status"] == "complete" and len(poses) == 2
    verdict = css(browser, "#verdict").text
    assert verdict.startswith("complete: 2 certified pose(s)"), verdict
    # one picture per pose, and the overlay of both
    wait(browser, lambda d: pictures_loaded(d, "figure.picture-box img") == 3, 120, "pictures")
    assert pictures_loaded(browser, "article.pose img") == 2
    # the tensions of every pose, as the result has them
    for k, pose in enumerate(poses):
        rows = css_all(browser, f'article.pose[data-pose="{k}"] table.tensions tbody tr')
        shown = [float(r.find_elements("tag name", "td")[1].text) for r in rows]
        assert shown == pytest.approx(pose["tau"], rel=1e-4)
    # the raw JSON, one click away
    css(browser, "#raw-details summary").click()
    raw = json.loads(css(browser, "#raw-json").get_attribute("textContent"))
    assert raw["solutions"][0]["tau"] == poses[0]["tau"]


def test_spatial_fk_job_is_drawn_in_3d(browser, server):
    """MARIONET's T-platform (Merlet's Figs. 4, 5): 7 wires, one pose for u = 0."""
    form = open_home(browser, server, "fk")
    choose_robot(form, "marionet-t")
    wait(browser, lambda d: "7 wires" in css(d, "#form-fk .robot-info").text, 30, "the robot")
    assert form.find_element("css selector", '[name="params.u"]').get_attribute("value") == (
        "0, 0, 0, 0, 0, 0, 0"
    )  # prefilled: one value per wire
    job_id = submit_form(browser, form)
    wait(browser, lambda d: pictures_loaded(d, "article.pose img") == 1, 180, "the pose")
    (pose,) = server.job(job_id)["result"]["solutions"]
    rows = css_all(browser, 'article.pose[data-pose="0"] table.tensions tbody tr')
    assert [float(r.find_elements("tag name", "td")[1].text) for r in rows] == pytest.approx(
        pose["tau"], rel=1e-4
    )
    assert css(browser, "#verdict").text.startswith("complete: 1 certified pose(s)")
    screenshot(browser, "web-fk.png")


def test_map_job_from_the_form_shows_the_map(browser, server):
    form = open_home(browser, server, "isotropic-map")
    choose_robot(form, "krut-3")
    fill(form, "params.grid", "-100, 100, -100, 100")
    fill(form, "params.nx", "81")
    fill(form, "params.ny", "81")
    submit_form(browser, form)
    wait(browser, lambda d: pictures_loaded(d, "figure.picture-box img") == 1, 120, "the map")
    assert "map of 6561 grid points" in css(browser, "#verdict").text
    screenshot(browser, "web-map.png")


def test_a_long_solve_is_watched_and_cancelled_from_its_page(browser, server):
    form = open_home(browser, server, "solve")
    fill(form, "system", hard_system(8))
    job_id = submit_form(browser, form)
    wait(browser, lambda d: css_all(d, "#job-head progress"), 60, "the progress bar")
    wait(browser, lambda d: "boxes" in css(d, "#job-head .running").text, 60, "progress")
    assert server.job(job_id)["status"] == "running"
    screenshot(browser, "web-running.png")
    css(browser, "#job-head button.cancel").click()
    wait(browser, lambda d: css_all(d, "#verdict"), 60, "the cancelled job")
    assert server.job(job_id)["status"] == "cancelled"
    verdict = css(browser, "#verdict").text
    assert verdict.startswith("cancelled: partial result. incomplete"), verdict
    assert "complete:" not in verdict.split("incomplete")[0]


def test_a_job_is_cancelled_from_the_list(browser, server):
    job_id = server.submit({"kind": "solve", "system": hard_system(8)})
    server.wait(job_id, until=lambda j: j["status"] == "running", timeout=60)
    open_home(browser, server, "fk")
    row = f'#job-table tr[data-id="{job_id}"]'
    wait(browser, lambda d: css_all(d, f"{row} .spinner"), 30, "the running job in the list")
    screenshot(browser, "web-home.png")
    css(browser, f"{row} button.cancel").click()
    wait(browser, lambda d: css(d, row).get_attribute("data-status") == "cancelled", 30,
         "the list to show the job cancelled")  # fmt: skip
    assert server.job(job_id)["status"] == "cancelled"


def test_bad_input_is_answered_beside_the_field(browser, server, tmp_path):
    # a robot file whose first wire has tau_min > tau_max
    bad = json.loads(json.dumps(PLANAR))
    bad["wires"][0]["tau"] = [10, 0]
    path = tmp_path / "bad-robot.json"
    path.write_text(json.dumps(bad))
    form = open_home(browser, server, "fk")
    choose_robot(form, "@file")
    form.find_element("css selector", "input[name=robot-file]").send_keys(str(path))
    fill(form, "params.u", "0, 0, 0, 0")
    form.find_element("css selector", "button[type=submit]").click()
    expected = api_message(
        server, {"kind": "fk", "robot": bad, "params": {"u": [0, 0, 0, 0]}}, "robot.wires.0.tau"
    )
    wait(browser, lambda d: field_error(form, "robot") == expected, 30, "the robot error")
    assert "#/jobs/" not in browser.current_url  # nothing was submitted
    # a control vector of the wrong length, with a good robot
    choose_robot(form, "planar")
    fill(form, "params.u", "1, 2")
    form.find_element("css selector", "button[type=submit]").click()
    expected = api_message(
        server, {"kind": "fk", "robot": PLANAR, "params": {"u": [1, 2]}}, "params.u"
    )
    wait(browser, lambda d: field_error(form, "params.u") == expected, 30, "the u error")
    assert field_error(form, "robot") == ""
    # a file that is not JSON at all: said before anything is sent
    path.write_text("{not json")
    choose_robot(form, "@file")
    form.find_element("css selector", "input[name=robot-file]").send_keys(str(path))
    form.find_element("css selector", "button[type=submit]").click()
    wait(browser, lambda d: "is not JSON" in field_error(form, "robot"), 30, "the JSON error")


# -- the API reference offline, and results the page must count right -------------------------
@pytest.fixture(scope="module")
def offline_browser():
    """Chromium that can resolve no name but 127.0.0.1: any CDN request fails."""
    yield from _chromium("--host-resolver-rules=MAP * ~NOTFOUND , EXCLUDE 127.0.0.1")


@pytest.fixture(scope="module")
def idle_server(tmp_path_factory):
    """A service without workers: its jobs are finished by the test, with chosen results."""
    s = Server(tmp_path_factory.mktemp("idle") / "data", 0)
    yield s
    s.close()


REDOC_LOGO = "https://cdn.redoc.ly"


def loaded_from(driver) -> set[str]:
    """The origins of every resource the page loaded."""
    urls = driver.execute_script(
        "return [location.href, ...performance.getEntriesByType('resource').map(e => e.name)]"
    )
    return {re.match(r"^[a-z]+://[^/]+", u).group(0) for u in urls}


def console_errors(driver) -> list[str]:
    return [e["message"] for e in driver.get_log("browser") if e["level"] == "SEVERE"]


def test_api_reference_renders_offline(offline_browser, idle_server):
    """Swagger UI and ReDoc draw every operation with no network and no CSP complaint."""
    d = offline_browser
    paths = idle_server.http.get("/openapi.json").json()["paths"]
    operations = sum(len(ops) for ops in paths.values())
    d.get(idle_server.base + "/docs")
    wait(d, lambda d: len(css_all(d, ".opblock")) == operations, 60, "Swagger UI's operations")
    assert "/v1/jobs/{job_id}" in css(d, "#swagger-ui").text
    d.get(idle_server.base + "/redoc")
    wait(d, lambda d: len(css_all(d, '[data-section-id^="operation/"]')) == operations, 60,
         "ReDoc's operations")  # fmt: skip
    assert "Submit" in css(d, "redoc").text or "submit" in css(d, "redoc").text
    # ReDoc's sidebar tries a decorative logo from its CDN (hidden when it fails to load);
    # the CSP refuses it, and nothing else leaves the service
    assert loaded_from(d) - {REDOC_LOGO} == {idle_server.base}
    assert [e for e in console_errors(d) if REDOC_LOGO not in e] == []


def finish_job(server, job: dict, status: str, result: dict, progress: dict) -> str:
    """Submit ``job`` to the idle server, then end it here with ``result``."""
    from certsolve.jobs.store import JobStore

    job_id = server.submit(job)
    store = JobStore(server.data_dir / "jobs.sqlite3")
    try:
        claimed, lease = store.claim(os.getpid())
        assert claimed.id == job_id
        assert store.finish(job_id, lease, status, result=json.dumps(result), progress=progress)
    finally:
        store.close()
    return job_id


def test_a_cancelled_job_counts_its_pending_boxes_not_their_groups(offline_browser, idle_server):
    d = offline_browser
    hulls = [[[0.0, 1.0]] * 3] * 1000  # the stored list: 1000 hulls of 6131 boxes
    result = {
        "robot": "planar", "formulation": "platform", "u": [0.8, 1.8, -2.5, -3.6],
        "status": "cancelled", "solutions": [], "variables": ["x", "y", "t"],
        "undecided": [{"box": [[0, 1]] * 3, "reason": "eps", "boxes": 7}],
        "pending": hulls, "undecided_total": 7, "undecided_dropped": 0, "pending_total": 6131,
        "pending_boxes": [6] * 1000, "stats": {"boxes": 9000, "stopped_by": "cancelled"},
    }  # fmt: skip
    job = {"kind": "fk", "robot": PLANAR, "params": {"u": [0.8, 1.8, -2.5, -3.6]}}
    progress = {"boxes": 9000, "pending": 6131, "undecided": 7}
    job_id = finish_job(idle_server, job, "cancelled", result, progress)
    d.get(f"{idle_server.base}/#/jobs/{job_id}")
    d.refresh()
    wait(d, lambda d: css_all(d, "#verdict"), 30, "the verdict")
    verdict = css(d, "#verdict").text
    assert "7 undecided and 6131 pending box(es)" in verdict, verdict
    text = css(d, "#job-result").text
    assert "6131 pending box(es): the search stopped" in text, text
    assert "7 undecided box(es) in 1 group(s)" in text, text
    assert [b.text.lower() for b in css_all(d, "#job-head .badge")] == ["cancelled", "incomplete"]
    assert console_errors(d) == []  # nothing refused by the Content-Security-Policy


def test_a_complete_workspace_has_no_incomplete_badge(offline_browser, idle_server):
    """Its boundary boxes are counted as undecided in its progress: not a worry."""
    d = offline_browser
    krut3 = json.loads((ROOT / "examples/robots/krut-3.json").read_text())
    params = {"min_force": 100, "box": [[-90, 90], [-100, 50]], "eps": 10}
    counts = {"inside": 40, "outside": 30, "boundary": 12, "pending": 0}
    result = {
        "robot": "krut-3", "min_force": 100, "status": "complete", "counts": counts,
        "inside_measure": 1234.5, "unit": "cm²", "inside_share": 0.45, "boxes": 150,
    }  # fmt: skip
    progress = {"boxes": 150, "solutions": 40, "undecided": 12, "pending": 0}
    job = {"kind": "workspace", "robot": krut3, "params": params}
    job_id = finish_job(idle_server, job, "done", result, progress)
    d.get(f"{idle_server.base}/#/jobs/{job_id}")
    d.refresh()
    wait(d, lambda d: css_all(d, "#verdict"), 30, "the verdict")
    assert css(d, "#verdict").text.startswith("complete:")
    assert [b.text.lower() for b in css_all(d, "#job-head .badge")] == ["done"]
    d.get(f"{idle_server.base}/#/")
    row = f'#job-table tr[data-id="{job_id}"]'
    wait(d, lambda d: css_all(d, row), 30, "the job list")
    assert [b.text.lower() for b in css_all(d, f"{row} .badge")] == ["done"]


def test_the_token_is_sent_but_not_stored(offline_browser, tmp_path_factory):
    """A service with tokens: the typed token is sent with every call, kept in the page's
    memory only (not in sessionStorage), and asked for again after a reload."""
    d = offline_browser
    data = tmp_path_factory.mktemp("tokens")
    token = "page-token-0123456789abcdef"
    (data / "tokens.json").write_text(json.dumps({"ada": {"token": token}}))
    server = Server(data / "data", 0, "--tokens", str(data / "tokens.json"))
    try:
        d.get(server.base + "/#/")
        d.refresh()
        wait(d, lambda d: "access token" in css(d, "#banner").text, 30, "the token banner")
        box = css(d, "#token")
        box.send_keys(token)
        css(d, "#jobs h2").click()  # leaves the field: its change event
        wait(d, lambda d: css_all(d, "#form-fk select[name=robot] option[value=planar]"), 30,
             "the robots, read with the token")  # fmt: skip
        headers = {"Authorization": f"Bearer {token}"}
        job = {"kind": "fk", "robot": PLANAR, "params": {"u": [0, 0, 0, 0]}}
        job_id = server.http.post("/v1/jobs", json=job, headers=headers).json()["id"]
        row = f'#job-table tr[data-id="{job_id}"]'
        wait(d, lambda d: css_all(d, row), 30, "the job listed with the token")
        stored = d.execute_script(
            "return Object.keys(sessionStorage).map(k => sessionStorage.getItem(k))"
        )
        assert token not in stored, stored
        d.refresh()
        wait(d, lambda d: "access token" in css(d, "#banner").text, 30, "asked again")
        assert css(d, "#token").get_attribute("value") == ""
    finally:
        server.close()


def test_the_pose_boxes_of_a_robot_with_tolerances_are_drawn(offline_browser, idle_server):
    """An FK job on a robot with tolerances: every attachment's bounds over the set, drawn
    in two projections as the result has them, with their hull."""
    from certsolve.jobs.partial import stored_result
    from certsolve.kinematics import forward_kinematics
    from certsolve.robot import Robot

    d = offline_browser
    robot = json.loads((ROOT / "examples/robots/marionet-t-tol.json").read_text())
    u = [0.0] * 7
    result = stored_result(forward_kinematics(Robot.load(robot), u), 1000)
    (pose,) = result["solutions"]
    job = {"kind": "fk", "robot": robot, "params": {"u": u}}
    progress = {"boxes": result["stats"]["boxes"], "solutions": 1}
    job_id = finish_job(idle_server, job, "done", result, progress)
    d.get_log("browser")  # reading empties it: what the tests before left there goes
    d.get(f"{idle_server.base}/#/jobs/{job_id}")
    d.refresh()
    panels = 'article.pose[data-pose="0"] figure.pose-set svg'
    wait(d, lambda d: len(css_all(d, panels)) == 2, 30, "the pose boxes")
    lo, hi = np.array(pose["platform_points_lo"]), np.array(pose["platform_points_hi"])
    for svg, (a, b) in zip(css_all(d, panels), [(0, 1), (0, 2)], strict=True):
        rects = svg.find_elements("css selector", "rect.pp-box")
        assert len(rects) == 7
        # one scale on both axes: each rectangle's sides are its bounds' widths times it
        w = np.array([float(r.get_attribute("width")) for r in rects])
        h = np.array([float(r.get_attribute("height")) for r in rects])
        assert w / h == pytest.approx((hi[:, a] - lo[:, a]) / (hi[:, b] - lo[:, b]), rel=1e-3)
        title = rects[0].find_element("tag name", "title").get_attribute("textContent")
        assert title.startswith("wire 1:") and f"{lo[0, a]:.6g}"[:6] in title
        hull = svg.find_element("css selector", "polygon.pp-hull").get_attribute("points")
        assert len(hull.split()) >= (3 if b == 1 else 2)  # T-16: three points, flat in z
    assert "position bounds (cm)" in css(d, "#job-result").text
    wait(d, lambda d: pictures_loaded(d, "article.pose img") == 1, 120, "the pose picture")
    assert console_errors(d) == []
    screenshot(d, "web-fk-tolerances.png")
