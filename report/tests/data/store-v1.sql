-- A results store of schema 1, frozen as ppmc 0.1.0 wrote it (issue 31):
-- harness/tests/store.rs checks that every later ppmc still reads it.
-- Never edit it; when the schema changes, add a store of the new one beside.
CREATE TABLE runs (
    id              INTEGER PRIMARY KEY,
    started         TEXT    NOT NULL,  -- RFC 3339, UTC
    harness_version TEXT    NOT NULL,
    git_revision    TEXT    NOT NULL,
    host            TEXT    NOT NULL,
    source          TEXT    NOT NULL,  -- 'boards' or 'capture'
    wall_s          REAL    NOT NULL,
    passed          INTEGER NOT NULL,
    marginal        INTEGER NOT NULL,
    flaky           INTEGER NOT NULL,
    failed          INTEGER NOT NULL,
    errors          INTEGER NOT NULL,
    not_run         INTEGER NOT NULL,
    record          TEXT    NOT NULL   -- the JSON run record, without its figures
);
CREATE TABLE boards (
    id              INTEGER PRIMARY KEY,
    run_id          INTEGER NOT NULL REFERENCES runs(id),
    name            TEXT    NOT NULL,
    target          TEXT    NOT NULL,
    board_serial    TEXT,
    board_rev       TEXT,
    bridge_firmware TEXT,
    bridge_serial   TEXT,
    reached         INTEGER NOT NULL   -- 0: the board took no part
);
CREATE TABLE results (
    id         INTEGER PRIMARY KEY,
    run_id     INTEGER NOT NULL REFERENCES runs(id),
    board_id   INTEGER REFERENCES boards(id),
    scenario   TEXT    NOT NULL,
    section    TEXT    NOT NULL,
    pass       INTEGER,
    verdict    TEXT    NOT NULL,  -- passed, marginal, flaky, failed, error, not_run
    blame      TEXT,              -- judged from a capture: board, host or capture
    attempts   INTEGER NOT NULL,  -- how many times it ran
    elapsed_ns INTEGER NOT NULL,
    detail     TEXT
);
CREATE TABLE measurements (
    result_id      INTEGER NOT NULL REFERENCES results(id),
    name           TEXT    NOT NULL,
    value_ns       INTEGER NOT NULL,
    lo_ns          INTEGER NOT NULL,
    hi_ns          INTEGER,          -- NULL: no upper limit
    marginal_lo_ns INTEGER NOT NULL,
    marginal_hi_ns INTEGER,
    grade          TEXT    NOT NULL
);
CREATE INDEX boards_run ON boards(run_id);
CREATE INDEX boards_rev ON boards(board_rev, board_serial);
CREATE INDEX results_run ON results(run_id);
CREATE INDEX results_board ON results(board_id);
CREATE INDEX results_scenario ON results(scenario);
CREATE INDEX measurements_result ON measurements(result_id);
CREATE INDEX measurements_name ON measurements(name);

INSERT INTO runs VALUES (1, '2026-11-20T10:00:00Z', '0.1.0', 'd3de167d47ac', 'lab-1', 'boards', 1.5,
    2, 0, 0, 0, 0, 0, '{"format":"ppmc-run-record/4"}');
INSERT INTO runs VALUES (2, '2026-11-21T10:00:00Z', '0.1.0', 'd3de167d47ac', 'lab-1', 'boards', 1.6,
    1, 0, 0, 1, 0, 0, '{"format":"ppmc-run-record/4"}');
INSERT INTO boards VALUES (1, 1, 'emu', 'emu', 'A-0001', 'A', NULL, NULL, 1);
INSERT INTO boards VALUES (2, 2, 'bench-2', 'serial:/dev/ttyACM0', 'B-0001', 'B', 'ppmc-bridge-rp2350 0.1.0', 'E6614C311B4E5A2F', 1);
INSERT INTO results VALUES (1, 1, 1, 's3_3_4_accel_trapezoid_200_steps', '3-3-4', NULL, 'passed', NULL, 1, 181402000, NULL);
INSERT INTO results VALUES (2, 1, 1, 's3_3_5_constant_speed_100_steps', '3-3-5', NULL, 'passed', NULL, 1, 174978000, NULL);
INSERT INTO results VALUES (3, 2, 2, 's3_3_4_accel_trapezoid_200_steps', '3-3-4', NULL, 'failed', NULL, 1, 181412000,
    'accel_first_pout (Table 3-3): expected 198.000us..=1111.000us, got 1200.000us');
INSERT INTO results VALUES (4, 2, 2, 's3_3_5_constant_speed_100_steps', '3-3-5', NULL, 'flaky', NULL, 2, 174978000, NULL);
INSERT INTO measurements VALUES (1, 'accel_first_pout', 200000, 198000, 1111000, 200282, 1108222, 'PASS');
INSERT INTO measurements VALUES (3, 'accel_first_pout', 1200000, 198000, 1111000, 200282, 1108222, 'FAIL');
PRAGMA user_version = 1;
