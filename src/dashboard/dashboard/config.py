"""The dashboard node's parameters (units and ranges; config/dashboard.yaml carries them)."""

from motion_common.params import Param, ParamSchema

DASHBOARD_PARAMETERS = ParamSchema(
    [
        Param("host", "127.0.0.1", doc="address to serve on; anything but 127.0.0.1/localhost needs a token"),
        Param("port", 8080, "", "TCP port of the page", low=1, high=65535),
        Param(
            "token",
            "",
            doc="access token (?token= in the URL); required with a non-local host; at least 64 bits "
            "(16 random hex digits); prefer token_file or the environment variable MOTION_DASHBOARD_TOKEN",
        ),
        Param(
            "token_file",
            "",
            doc="file holding the access token (first line; mode 600): keeps it off the "
            "command line and the parameter server",
        ),
        Param(
            "allowed_hosts",
            [],
            item_kind=str,
            doc="more names the page may be opened as (Host header), besides "
            "loopback, host, and this machine's name and addresses when host is 0.0.0.0",
        ),
        Param("refresh_s", 0.2, "s", "page refresh period", low=0.05, high=5.0),
        Param("path_points", 400, "points", "points kept per path in the plot", low=2, high=10000),
        Param("path_interval_s", 0.05, "s", "minimum time between two kept path points", low=0.0, high=10.0),
        Param("latency_window", 500, "commands", "commands in the latency p50/p99", low=1, high=100000),
        Param("stale_after_s", 2.0, "s", "a reading older than this is shown as stale", low=0.1, high=60.0),
        Param("programs_dir", "output/programs", doc="folder of taught programs (teach mode saves there)"),
        Param("scene", "", doc="scene YAML the program check clears segments against (empty: none)"),
        Param("output_dir", "output", doc="folder kitting campaigns write their summary to"),
        Param("campaign_trials", 6, "trials", "default trials of a campaign started here", low=1, high=1000),
        Param("engage_mode", "", doc="the core's engage mode (empty: read /motion_commander/engage)"),
        Param("title", "Motion teleop dashboard", doc="page title"),
        Param(
            "application",
            "auto",
            doc="the session's application, which decides the panels shown (auto: from the running graph's topics)",
            choices=("auto", "teleop", "teach", "kitting"),
        ),
        Param("device", "", doc="the session's input device (its launch's device argument; empty: not given)"),
        Param("urdf", "", doc="robot URDF of the 3-D view and the joint limits (empty: /robot_description)"),
        Param("scene_rate", 10.0, "Hz", "3-D view refresh rate (a timer, never per message)", low=1.0, high=30.0),
        Param("camera_rate", 2.0, "Hz", "camera image refresh rate on the page", low=0.2, high=10.0),
        Param("series_points", 600, "points", "samples kept per time series", low=10, high=100000),
        Param("series_interval_s", 0.1, "s", "minimum time between two kept samples of a series", low=0.0, high=10.0),
        Param("events", 200, "events", "events kept in the log", low=10, high=10000),
    ]
)
