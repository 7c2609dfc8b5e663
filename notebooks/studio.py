# %% [markdown]
# # The cam workbench in a notebook
#
# `camjax.studio.show` serves the workbench of `camjax studio` from a background thread of
# this kernel and shows it in the cell: edit the segments and the follower, and the lift,
# the profile, the response at one speed and the report over the speed range are redrawn
# (docs/studio.md).  The frame needs the live kernel: on the static documentation site it
# stays empty.

# %%
import camjax
from camjax import program as cp
from camjax.studio import show

cam = camjax.Program.load(cp.example_path("feed"))
frame = show(cam, rpm="200:1400:7")
print(f"workbench at {frame.studio.url}")
frame

# %% [markdown]
# The page's program is the kernel's too: `frame.studio` holds every page's workbench, and
# the JSON API answers from Python as it does to the page (`GET /api/report` is the report
# of `camjax program --format json`).  Stop the server when done:

# %%
import json
import urllib.request

with urllib.request.urlopen(f"{frame.studio.url.rstrip('/')}/api/report?session=notebook") as answer:
    served = json.load(answer)
print(f"jump speed served to the page: {served['jump_speed_rpm']:.2f} rpm")
frame.studio.stop()
