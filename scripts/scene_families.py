"""Scene families: scenario files drawn at random from a family's distribution, so a
Monte Carlo over fresh seeds measures the vision on scenes nobody tuned it to.

    import scene_families
    scenario = scene_families.draw("landing_tiles", seed)   # a dict: a config/scenarios file

A family is a distribution over everything a scenario holds: surfaces textured from many
photographs (OpenCV's sample images from Debian's opencv-doc, none of those the vision tests
use), tiled and low-texture floors, platforms of many sizes and turns, openings of several
sizes, aspect ratios and offsets in walls of several thicknesses, wind with gusts, exposure blur
and gain flicker. The same (family, seed) always gives the same scenario; scripts/scenes writes
them to files and scripts/montecarlo --families flies them.

A real camera's effects (the scenario's camera.effects and vibration blocks) join any
family by name: "landing_photo+rolling_shutter" is landing_photo's scene for that seed (the same
scene, drawn from the same stream) with a rolling shutter of a drawn line delay;
"ingress_photo+vibration+driver" adds two; "+camera" adds them all. EFFECTS lists them.
"""
import math
import os
import random

PHOTO_DIR = "/usr/share/doc/opencv-doc/examples/data"
# Photographs for floors, walls and the room behind an opening. Disjoint from the ones the
# vision tests warp (aero1, aero3, baboon, building, graf1) and from the platform-top pool.
SURFACE_PHOTOS = ["aloeL.jpg", "board.jpg", "box_in_scene.png", "ela_original.jpg", "home.jpg",
                  "leuvenA.jpg", "pca_test1.jpg", "rubberwhale1.png", "squirrel_cls.jpg",
                  "starry_night.jpg", "stuff.jpg", "graf3.png", "basketball1.png", "left.jpg",
                  "licenseplate_motion.jpg", "Blender_Suzanne1.jpg"]
# The vehicle files' search rectangle (autonomy.detection.landing_area_{min,max}_W_m) [m].
LANDING_AREA_MIN, LANDING_AREA_MAX = (-0.2, -0.5), (2.0, 1.5)
# Photographs with large smooth regions (half or more of their 32-pixel blocks at 512 pixels
# wide vary by under 6 grey levels: sky, a painted wall, a backdrop) for walls, and busy ones
# for the room behind an opening.
SMOOTH_PHOTOS = ["ela_original.jpg", "ela_modified.jpg", "stuff.jpg", "Blender_Suzanne1.jpg",
                 "Blender_Suzanne2.jpg", "home.jpg"]
BUSY_PHOTOS = ["starry_night.jpg", "board.jpg", "box_in_scene.png", "leuvenA.jpg",
               "rubberwhale1.png", "squirrel_cls.jpg", "pca_test1.jpg", "basketball1.png"]
# Photographs printed on a platform's top (a poster, a magazine, a box lid).
TOP_PHOTOS = ["sudoku.png", "smarties.png", "butterfly.jpg", "messi5.jpg", "fruits.jpg",
              "apple.jpg", "orange.jpg", "chicky_512.png", "text_motion.jpg", "rubberwhale2.png"]

FAMILIES = {
    "landing_photo": "photographed floor and platform tops, any size and turn, wind, blur, flicker",
    "landing_tiles": "floor of flat grey tiles 20-40 cm (features only at their corners)",
    "landing_lowtex": "pale low-contrast floor and a nearly blank paper platform",
    "landing_none_photo": "a photographed floor and no platform: nothing may be found",
    "ingress_photo": "photographed wall and room, openings of many sizes, shapes and offsets",
    "ingress_solid_photo": "a photographed wall without an opening: nothing may be found",
    "landing_sizes": "platforms from 20 cm to 1.4 m long, the largest wider than the downward "
                     "camera's view from the search height, on a photographed floor",
    "landing_samegrain": "floor and top cut from one photograph at one scale: natural textures of "
                         "the same grain on both (gravel on gravel)",
    "landing_dim": "a nearly featureless dark top (slate) on a speckled floor (granite) in dim "
                   "light, a third of the usual ambient, sensor noise 4-6 grey levels",
    "landing_wet": "a wet or glazed top mirroring the sky (clouds 20-60 m up) or a hall's ceiling "
                   "(2-3.5 m above it), 10-40 % (clouds) or 5-25 % (a ceiling) of its brightness "
                   "mirrored seen straight down, on photographed floors and tops",
    "landing_shadows": "a low sun (15-40 deg up) and hard shadows on a photographed floor and "
                       "top: the platform's own across the floor, a mast's or a parapet's across "
                       "the top",
    "ingress_smooth_wall": "a photographed wall with large smooth regions and a busy photographed "
                           "room behind the opening",
    "landing_moving_cart": "a platform on a flat cart going round a path (line, circle, figure "
                           "eight) at 0.5-1 m/s, slowing for its turns (course turning at 8-15 "
                           "deg/s), half of them turning with the path, photographed floor, wind",
    "landing_deck": "a platform on a boat's deck going round a path at 0.2-0.5 m/s, slowing for "
                    "its turns as the cart does, heaving up to 5 cm and rolling and pitching up "
                    "to 3 deg (random sea, 0.2-0.5 Hz), wind",
    "landing_moving_cart_agile": "the paths of landing_moving_cart taken at full speed through "
                                 "their 0.4-0.8 m turns (the course turning at 36-143 deg/s, "
                                 "past the issue's 15 deg/s), the heading kept",
    "landing_deck_agile": "the paths of landing_deck taken at full speed through their turns "
                          "(14-72 deg/s), the heading kept",
}
# Families that fly another's scenes with one thing changed (the same draws, the same seed).
AGILE = {"landing_moving_cart_agile": "landing_moving_cart", "landing_deck_agile": "landing_deck"}

# The simulator's limits for a moving platform (sim/params.hpp, PlatformMotionParams).
MAX_PLATFORM_SPEED_MPS = 1.0
MAX_PLATFORM_RATE_DPS = 15.0

# Camera effects (sim/camera_effects.hpp), each drawn from a stream of its own so adding one
# leaves the scene and the other effects' draws as they were.
EFFECTS = {
    "rolling_shutter": "rolling shutter, line delay 10-40 us (5-20 ms readout)",
    "exposure_steps": "automatic-exposure steps of up to 1-2 EV, 0.3-1 per second, lag 3-10 frames",
    "vibration": "motor vibration 80-125 Hz and its 2nd harmonic, 0.5-3 mrad, 10-100 um; the IMU too",
    "vignetting": "radial falloff to 40-80 % in the corners",
    "lens_radtan": "radial-tangential (plumb_bob) distortion, k1 -0.3..-0.1 (barrel)",
    "lens_fisheye": "an equidistant (fisheye) lens, k1 -0.05..0.05",
    "driver": "1-5 % frames dropped, 1-5 % repeated, stamp jitter 0.5-2 ms",
}


def _effect(rng, name, s):
    fx = s["camera"].setdefault("effects", {})
    if name == "rolling_shutter":
        fx["rolling_shutter"] = {"enabled": True,
                                 "line_delay_s": round(rng.uniform(10e-6, 40e-6), 8)}
    elif name == "exposure_steps":
        fx["exposure_steps"] = {"enabled": True, "max_ev": round(rng.uniform(1.0, 2.0), 2),
                                "rate_hz": round(rng.uniform(0.3, 1.0), 2),
                                "lag_frames": rng.randint(3, 10)}
    elif name == "vibration":
        s["vibration"] = {"enabled": True, "base_hz": round(rng.uniform(80, 125), 1),
                          "harmonics": 2, "angle_rad": round(rng.uniform(0.0005, 0.003), 5),
                          "linear_m": round(rng.uniform(1e-5, 1e-4), 6), "imu_share": 1.0}
    elif name == "vignetting":
        fx["vignetting"] = {"enabled": True, "corner_ratio": round(rng.uniform(0.4, 0.8), 3)}
    elif name == "lens_radtan":
        fx["lens"] = {"enabled": True, "model": "plumb_bob",
                      "coefficients": [round(rng.uniform(-0.3, -0.1), 4),
                                       round(rng.uniform(0.02, 0.1), 4),
                                       round(rng.uniform(-0.001, 0.001), 5),
                                       round(rng.uniform(-0.001, 0.001), 5), 0.0]}
    elif name == "lens_fisheye":
        fx["lens"] = {"enabled": True, "model": "equidistant",
                      "coefficients": [round(rng.uniform(-0.05, 0.05), 4),
                                       round(rng.uniform(-0.01, 0.01), 4), 0.0, 0.0, 0.0]}
    else:
        assert name == "driver"
        fx["driver"] = {"enabled": True, "drop_prob": round(rng.uniform(0.01, 0.05), 3),
                        "dup_prob": round(rng.uniform(0.01, 0.05), 3),
                        "stamp_jitter_s": round(rng.uniform(0.0005, 0.002), 5)}


def split(family):
    """(base family, [effects]) of a name such as landing_photo+rolling_shutter; "+camera" is
    every effect but the fisheye (one lens at a time)."""
    base, *effects = family.split("+")
    out = []
    for e in effects:
        out += [k for k in EFFECTS if k != "lens_fisheye"] if e == "camera" else [e]
    return base, out


def known(family):
    base, effects = split(family)
    return base in FAMILIES and all(e in EFFECTS for e in effects)


def describe(family):
    base, effects = split(family)
    return "; ".join([FAMILIES[base]] + [EFFECTS[e] for e in effects])


# Flying area, sensors and sim step as in the shipped scenarios (config/scenarios/landing_a.yaml).
_MOCAP = {"rate_hz": 100, "latency_s": 0.010, "pos_sigma_m": 0.0003, "rot_sigma_rad": 0.0015,
          "vel_sigma_mps": 0.005, "rate_sigma_radps": 0.01}
_IMU = {"rate_hz": 200, "accel_sigma_mps2": 0.04, "gyro_sigma_radps": 0.003,
        "accel_bias_sigma_mps2": 0.05, "gyro_bias_sigma_radps": 0.005}


def _pow2_width(path):
    # The renderer scales an image down to power-of-two sides (sim/texture.cpp); the texel size
    # applies to those pixels.
    from PIL import Image  # python3-pil: a dependency of python3-matplotlib
    with Image.open(path) as im:
        w = im.size[0]
    p = 1
    while p * 2 <= min(w, 4096):
        p *= 2
    return p


def _photo(rng, pool, extent_m):
    """An image texture from the pool, one copy spanning extent_m (the surface repeats it)."""
    path = os.path.join(PHOTO_DIR, rng.choice(pool))
    return {"kind": "image", "path": path, "texel_m": round(extent_m / _pow2_width(path), 6)}


def _procedural(rng, kind, size_px, texel_m, mean, contrast, feature_m):
    return {"kind": kind, "seed": rng.randint(1, 999), "size_px": size_px, "texel_m": texel_m,
            "mean": round(mean, 1), "contrast": round(contrast, 3), "feature_m": round(feature_m, 4)}


def _wind(rng, steady_max, gust_max):
    speed = rng.uniform(0.0, steady_max)
    heading = rng.uniform(0.0, 2 * math.pi)
    return {"steady_mps": [round(speed * math.cos(heading), 3), round(speed * math.sin(heading), 3), 0.0],
            "gust_sigma_mps": round(rng.uniform(0.0, gust_max), 3),
            "gust_tau_s": round(rng.uniform(0.5, 2.0), 2)}


def _camera(rng, mount):
    # Exposure 2-12 ms smeared over several samples, sensor noise, frame-to-frame gain flicker.
    return {"mount": mount, "rate_hz": 30, "exposure_s": round(rng.uniform(0.002, 0.012), 4),
            "noise_sigma": round(rng.uniform(1.0, 3.0), 2), "motion_blur_samples": 4,
            "gain_jitter": round(rng.uniform(0.0, 0.06), 3)}


def _lighting(rng, light_dir):
    return {"ambient": round(rng.uniform(0.6, 0.85), 3), "diffuse": round(rng.uniform(0.2, 0.45), 3),
            "light_dir_W": light_dir, "gain": round(rng.uniform(0.85, 1.15), 3),
            "lamp_W": [round(rng.uniform(-2, 2), 2), round(rng.uniform(-2, 2), 2), 3.0],
            "lamp_radius_m": 3.0}


def _sunlit(rng, scene):
    """Outdoors under a low sun: direct light 15-40 deg above the horizon from any side, an
    ambient (sky) share of 20-35 %, no lamp, shadows cast; the gain keeps a sunlit floor as bright
    as the halls' (shade 1). One or two casters out of view lay their shadows over the platform:
    a mast (a thin stripe) or a parapet (a straight edge across the top)."""
    elevation = math.radians(rng.uniform(15.0, 40.0))
    azimuth = rng.uniform(0.0, 2 * math.pi)
    sun = [math.cos(elevation) * math.cos(azimuth), math.cos(elevation) * math.sin(azimuth),
           math.sin(elevation)]
    ambient = rng.uniform(0.20, 0.35)
    diffuse = 1.0 - ambient
    lit = ambient + diffuse * math.sin(elevation)
    scene["lighting"] = {"ambient": round(ambient, 3), "diffuse": round(diffuse, 3),
                         "light_dir_W": [round(v, 4) for v in sun], "gain": round(1.0 / lit, 3),
                         "falloff": 0.0, "shadows": True, "casters": []}
    scene["randomize"].update({"light_dir_deg": 0, "light_falloff": 0.0})
    p = scene["platform"]
    cx, cy = p["center_xy_m"]
    length, width, top = p["size_m"]
    toward = (math.cos(azimuth), math.sin(azimuth))   # from the platform towards the sun
    across = (-toward[1], toward[0])
    half = [0.5 * v for v in scene["area"]["size_m"]]
    # Where the way towards the sun leaves the flying area: the casters stand beyond it.
    exit_m = min(((half[i] - c * (1 if toward[i] > 0 else -1)) / abs(toward[i])
                  for i, c in enumerate((cx, cy)) if abs(toward[i]) > 1e-6), default=half[0])
    for _ in range(rng.choice((1, 2))):
        distance = exit_m + rng.uniform(0.3, 1.5)
        side = rng.uniform(-0.5, 0.5) * min(length, width)
        while True:
            x = cx + toward[0] * distance + across[0] * side
            y = cy + toward[1] * distance + across[1] * side
            if max(abs(x) - half[0], abs(y) - half[1]) > 0.1:
                break
            distance += 0.1
        yaw = math.degrees(azimuth)
        if rng.random() < 0.5:  # a mast: its shadow runs over the whole top
            thick = rng.uniform(0.06, 0.25)
            height = top + (distance + max(length, width)) * math.tan(elevation) * rng.uniform(1.1, 2.0)
            caster = [x, y, thick, thick, height, yaw]
        else:  # a parapet across the sun: its shadow's edge falls on the top
            reach = distance + rng.uniform(-0.5, 0.5) * min(length, width)
            caster = [x, y, 0.2, rng.uniform(4.0, 8.0), top + reach * math.tan(elevation), yaw]
        scene["lighting"]["casters"].append([round(v, 3) for v in caster])
    return scene


def _wet(rng, scene):
    """The platform's top wet or glazed: outdoors it mirrors clouds (soft blobs metres across,
    20-60 m up), indoors a hall's ceiling 2-3.5 m above it (a busy photograph: pipes, lamps,
    beams). The share of the top's brightness mirrored straight down is Fresnel's 2 % (water)
    to 4 % (glass) of the mirrored surface's radiance against the top's own: a top of albedo
    0.05-0.2 under a sky lit as brightly is 10-40 % mirror; a ceiling lit by the hall's lamps is
    a few times darker than the sky, 5-25 %."""
    if rng.random() < 0.5:
        sky = _procedural(rng, "blobs", 1024, round(rng.uniform(0.05, 0.15), 3),
                          rng.uniform(170, 235), rng.uniform(0.3, 0.8), rng.uniform(3.0, 10.0))
        height, share = rng.uniform(20.0, 60.0), rng.uniform(0.10, 0.40)
    else:
        sky = _photo(rng, BUSY_PHOTOS, rng.uniform(3.0, 6.0))
        height, share = rng.uniform(2.0, 3.5), rng.uniform(0.05, 0.25)
    scene["platform"]["reflection"] = {"reflectance": round(share, 3),
                                       "sky_height_m": round(height, 2), "sky": sky}
    return scene


def _landing(rng, name, floor, platform):
    s = {
        "name": name,
        "sim": {"physics_dt_s": 0.001, "start_utime": 1700000000000000},
        "area": {"size_m": [6.0, 6.0], "center_xy_m": [0.0, 0.0], "height_m": 4.0,
                 "floor_texture": floor},
        "wind": _wind(rng, 0.7, 0.4),
        "mocap": dict(_MOCAP), "imu": dict(_IMU),
        "camera": _camera(rng, "downward"),
        "lighting": _lighting(rng, [0.3, 0.2, 1.0]),
        "randomize": {"platform_xy_m": 0.0, "platform_yaw_deg": 0, "start_clearance_m": 0.5,
                      "light_gain": 0.15, "light_dir_deg": 30, "light_falloff": 0.2},
        "start": {"position_m": [0.0, 0.0, 0.0], "yaw_deg": 0.0},
    }
    if platform is not None:
        s["platform"] = platform
    return s


def _platform(rng, top_of_length):
    # Anything from a ream of paper to a small crate: long side 25-50 cm, short side 20-32 cm
    # (the gear footprint plus margins fits on all), 8-22 cm high, any turn.
    length = rng.uniform(0.25, 0.50)
    width = rng.uniform(0.20, min(0.32, length))
    # Anywhere in the vehicles' search rectangle (autonomy.detection.landing_area_*: x -0.2..2,
    # y -0.5..1.5) with its edges inside it and clear of the start.
    return {"center_xy_m": [round(rng.uniform(0.8, 1.6), 3), round(rng.uniform(-0.15, 1.15), 3)],
            "size_m": [round(length, 3), round(width, 3), round(rng.uniform(0.08, 0.22), 3)],
            "yaw_deg": round(rng.uniform(-90, 90), 1),
            "texture": top_of_length(length)}


def _top(rng, length_m):
    # A photograph at least as long as the top, so it shows one picture, not a repeated one.
    if rng.random() < 0.6:
        return _photo(rng, TOP_PHOTOS, length_m * rng.uniform(1.0, 1.3))
    return _procedural(rng, "paper", 1024, 0.001, rng.uniform(190, 215), rng.uniform(0.6, 1.0),
                       rng.uniform(0.006, 0.010))


def _platform_any_size(rng, top_of_length, area_min, area_max):
    """A platform 0.2-1.4 m long (log-uniform: as many small ones as large), 0.2-1.0 m wide,
    8-30 cm high, any turn, wholly inside the search rectangle and at least 0.35 m from the
    start (drawn again until it is)."""
    length = math.exp(rng.uniform(math.log(0.20), math.log(1.40)))
    width = rng.uniform(0.20, min(1.0, length))
    height = rng.uniform(0.08, 0.30)
    while True:
        yaw = math.radians(rng.uniform(-90, 90))
        hx = abs(math.cos(yaw)) * length / 2 + abs(math.sin(yaw)) * width / 2
        hy = abs(math.sin(yaw)) * length / 2 + abs(math.cos(yaw)) * width / 2
        cx = rng.uniform(area_min[0] + hx, area_max[0] - hx)
        cy = rng.uniform(area_min[1] + hy, area_max[1] - hy)
        if start_clearance([cx, cy], [length, width], math.degrees(yaw)) >= 0.35:
            break
    return {"center_xy_m": [round(cx, 3), round(cy, 3)],
            "size_m": [round(length, 3), round(width, 3), round(height, 3)],
            "yaw_deg": round(math.degrees(yaw), 1), "texture": top_of_length(length)}


def start_clearance(center_xy, size_xy, yaw_deg):
    """Distance from the start (the origin) to a platform's footprint [m]."""
    yaw = math.radians(yaw_deg)
    u = -math.cos(yaw) * center_xy[0] - math.sin(yaw) * center_xy[1]
    v = math.sin(yaw) * center_xy[0] - math.cos(yaw) * center_xy[1]
    return math.hypot(max(abs(u) - size_xy[0] / 2, 0.0), max(abs(v) - size_xy[1] / 2, 0.0))


def _ingress(rng, name, opening):
    wall_x = 3.0
    s = {
        "name": name,
        "sim": {"physics_dt_s": 0.001, "start_utime": 1700000000000000},
        "area": {"size_m": [9.0, 6.0], "center_xy_m": [1.5, 0.0], "height_m": 4.0,
                 "floor_texture": _floor_any(rng)},
        "wall": {"x_m": wall_x, "center_y_m": 0.0, "width_m": 4.0, "height_m": 2.5,
                 "thickness_m": round(rng.uniform(0.05, 0.30), 3), "room_depth_m": 3.0,
                 "texture": _photo(rng, SURFACE_PHOTOS, rng.uniform(1.5, 3.0)),
                 "room_texture": _photo(rng, SURFACE_PHOTOS, rng.uniform(1.5, 3.0))},
        "wind": _wind(rng, 0.4, 0.3),
        "mocap": dict(_MOCAP), "imu": dict(_IMU),
        "camera": _camera(rng, "forward"),
        "lighting": _lighting(rng, [-0.6, 0.3, 1.0]),
        "randomize": {"light_gain": 0.15, "light_dir_deg": 30, "light_falloff": 0.2},
        "start": {"position_m": [0.0, 0.0, 0.0], "yaw_deg": 0.0},
    }
    if opening is not None:
        s["wall"]["opening"] = opening
    return s


def _floor_any(rng):
    if rng.random() < 0.5:
        return _photo(rng, SURFACE_PHOTOS, rng.uniform(1.5, 3.0))
    return _procedural(rng, "noise", 2048, 0.003, rng.uniform(80, 150), rng.uniform(0.5, 1.0), 0.03)


def _opening(rng):
    # Windows and doors the Pelican and the STARMAC (67 and 75 cm across) fit through with room:
    # 85-130 cm wide, 55-110 cm high, centred anywhere 45 cm either side of the wall's middle and
    # 0.9-1.5 m up (the sill at least 35 cm above the floor).
    w = rng.uniform(0.85, 1.30)
    h = rng.uniform(0.55, 1.10)
    zc = rng.uniform(max(0.9, 0.35 + h / 2), 1.5)
    return {"center_yz_m": [round(rng.uniform(-0.45, 0.45), 3), round(zc, 3)],
            "size_m": [round(w, 3), round(h, 3)]}


def path_point(motion, s):
    """The path's offset (x, y) from its start after arc length s, in world axes: the same closed
    form as sim/platform_motion.cpp (left turns first, from path_heading_deg)."""
    kind, r = motion.get("path", "none"), motion.get("path_radius_m", 1.0)
    if kind == "none":
        return 0.0, 0.0

    def arc(u, sign):
        phi = u / r
        return r * math.sin(phi), sign * r * (1.0 - math.cos(phi))
    if kind == "circle":
        x, y = arc(math.fmod(s, 2 * math.pi * r), 1.0)
    elif kind == "figure_eight":
        lobe = 2 * math.pi * r
        u = math.fmod(s, 2 * lobe)
        x, y = arc(u, 1.0) if u < lobe else arc(u - lobe, -1.0)
    else:  # line: a stadium
        length, half = motion.get("path_length_m", 2.0), math.pi * r
        u = math.fmod(s, 2 * length + 2 * half)
        if u < length:
            x, y = u, 0.0
        elif u < length + half:
            x, y = arc(u - length, 1.0)
            x += length
        elif u < 2 * length + half:
            x, y = length - (u - length - half), 2 * r
        else:
            ax, ay = arc(u - 2 * length - half, 1.0)
            x, y = -ax, 2 * r - ay
    h = math.radians(motion.get("path_heading_deg", 0.0))
    return x * math.cos(h) - y * math.sin(h), x * math.sin(h) + y * math.cos(h)


def path_extent(motion):
    """Points along one period of the path (offsets from its start), every 5 cm."""
    r, kind = motion.get("path_radius_m", 1.0), motion.get("path", "none")
    period = {"none": 0.0, "circle": 2 * math.pi * r, "figure_eight": 4 * math.pi * r,
              "line": 2 * motion.get("path_length_m", 2.0) + 2 * math.pi * r}[kind]
    n = max(1, int(period / 0.05))
    return [path_point(motion, period * k / n) for k in range(n + 1)]


def _moving_platform(rng, scene, speed_range, deck):
    """Puts the scene's platform on a moving cart or deck: a path drawn at random, placed so that
    all of it keeps the platform inside the flying area (0.3 m margin) and its footprint 0.5 m
    from the start (the vehicle stands there until it takes off; its rotors reach 0.34 m)."""
    p = scene["platform"]
    reach = 0.5 * math.hypot(p["size_m"][0], p["size_m"][1])  # its corners from its centre
    motion = {"path": rng.choice(["line", "circle", "figure_eight"]),
              "speed_mps": round(rng.uniform(*speed_range), 3),
              "path_heading_deg": round(rng.uniform(-180, 180), 1),
              "path_length_m": round(rng.uniform(1.0, 2.0), 3),
              "path_radius_m": round(rng.uniform(0.4, 0.8), 3),
              # A cart that turned with its path would turn faster than the limit on these
              # radii; a slow turn of its own instead.
              "heading_follows_path": False,
              "yaw_rate_dps": round(rng.uniform(-5.0, 5.0), 2)}
    if deck:
        motion["sea_state"] = {"heave_m": round(rng.uniform(0.02, 0.05), 3),
                               "roll_deg": round(rng.uniform(1.0, 3.0), 2),
                               "pitch_deg": round(rng.uniform(1.0, 3.0), 2),
                               "band_hz": [0.2, 0.5], "components": 4}
    half = [0.5 * v for v in scene["area"]["size_m"]]
    margin = reach + 0.3
    # A long stadium may find no place in the area clear of the start: after each 2000 draws
    # the path shrinks by a tenth (its straights first), down to the draws' least.
    for shrink in range(12):
        points = path_extent(motion)
        for attempt in range(2000):
            if attempt % 50 == 49:  # no place for it this way round: turn the path
                motion["path_heading_deg"] = round(rng.uniform(-180, 180), 1)
                points = path_extent(motion)
            # It starts where a static platform of the other families stands: in the vehicles'
            # search rectangle (autonomy.detection.landing_area_*), so the first views may see it.
            cx, cy = rng.uniform(-0.2, 2.0), rng.uniform(-0.5, 1.5)
            inside = all(abs(cx + x) <= half[0] - margin and abs(cy + y) <= half[1] - margin
                         for x, y in points)
            clear = all(math.hypot(cx + x, cy + y) >= 0.5 + reach for x, y in points)
            if inside and clear:
                p["center_xy_m"] = [round(cx, 3), round(cy, 3)]
                p["motion"] = motion
                return scene
        if motion["path_length_m"] > 1.0:
            motion["path_length_m"] = round(max(1.0, 0.9 * motion["path_length_m"]), 3)
        else:
            motion["path_radius_m"] = round(max(0.4, 0.9 * motion["path_radius_m"]), 3)
    raise RuntimeError("no place for the path %r" % motion)


def _turning(rng, scene):
    """How the platform takes its path's turns, from a stream of its own (the path, its place and
    the rest of the scene are drawn as before it): slowing for them so that its course turns at
    most 8-15 deg/s, the issue's bound on a platform's turn (a cart, a car's roof or a boat turns
    no tighter at these speeds), and in half of the scenes turning with its path as a cart does
    (then with no turn of its own added, the sum within the bound)."""
    m = scene["platform"]["motion"]
    m["max_course_rate_dps"] = round(rng.uniform(8.0, MAX_PLATFORM_RATE_DPS), 2)
    if rng.random() < 0.5:
        m["heading_follows_path"] = True
        m["yaw_rate_dps"] = 0.0
    return scene


def draw(family, seed):
    """The scenario (a dict, as a config/scenarios file holds) that `seed` draws from `family`
    (a base family, optionally with camera effects: landing_photo+rolling_shutter)."""
    base, effects = split(family)
    if not known(family):
        raise KeyError("unknown scene family '%s' (known: %s; effects: %s)"
                       % (family, ", ".join(sorted(FAMILIES)), ", ".join(EFFECTS)))
    if base in AGILE:  # the same scene, the turns at full speed
        s = _draw(AGILE[base], seed)
        s["name"] = base
    else:
        s = _draw(base, seed)
        if base in AGILE.values():
            _turning(random.Random("%s/%d/turns" % (base, seed)), s)
    for e in effects:
        _effect(random.Random("%s/%d/%s" % (base, seed, e)), e, s)
    if effects:
        s["name"] = family
    return s


def _draw(family, seed):
    rng = random.Random("%s/%d" % (family, seed))
    if family == "landing_photo":
        return _landing(rng, family, _photo(rng, SURFACE_PHOTOS, rng.uniform(1.5, 3.0)),
                        _platform(rng, lambda length: _top(rng, length)))
    if family == "landing_tiles":
        floor = _procedural(rng, "tiles", 2048, 0.002, rng.uniform(110, 190), rng.uniform(0.5, 1.0),
                            rng.uniform(0.20, 0.40))
        return _landing(rng, family, floor, _platform(rng, lambda length: _top(rng, length)))
    if family == "landing_lowtex":
        floor = _procedural(rng, "noise", 2048, 0.003, rng.uniform(170, 210), rng.uniform(0.12, 0.3),
                            rng.uniform(0.02, 0.06))
        top = _procedural(rng, "paper", 1024, 0.001, rng.uniform(215, 235), rng.uniform(0.25, 0.5),
                          rng.uniform(0.006, 0.010))
        return _landing(rng, family, floor, _platform(rng, lambda length: top))
    if family == "landing_sizes":
        return _landing(rng, family, _photo(rng, SURFACE_PHOTOS, rng.uniform(1.5, 3.0)),
                        _platform_any_size(rng, lambda length: _top(rng, length),
                                           LANDING_AREA_MIN, LANDING_AREA_MAX))
    if family == "landing_samegrain":
        photo = _photo(rng, SURFACE_PHOTOS, rng.uniform(1.5, 3.0))
        return _landing(rng, family, photo, _platform(rng, lambda length: dict(photo)))
    if family == "landing_dim":
        floor = _procedural(rng, "noise", 2048, 0.002, rng.uniform(100, 150), rng.uniform(0.6, 1.0),
                            rng.uniform(0.004, 0.012))
        top = _procedural(rng, "paper", 1024, 0.001, rng.uniform(60, 90), rng.uniform(0.1, 0.25),
                          rng.uniform(0.006, 0.010))
        scene = _landing(rng, family, floor, _platform(rng, lambda length: top))
        scene["lighting"]["ambient"] = round(scene["lighting"]["ambient"] / 3, 3)
        scene["lighting"]["diffuse"] = round(scene["lighting"]["diffuse"] / 3, 3)
        scene["camera"]["noise_sigma"] = round(rng.uniform(4.0, 6.0), 2)
        return scene
    if family == "landing_shadows":
        return _sunlit(rng, _landing(rng, family, _photo(rng, SURFACE_PHOTOS, rng.uniform(1.5, 3.0)),
                                     _platform(rng, lambda length: _top(rng, length))))
    if family == "landing_wet":
        return _wet(rng, _landing(rng, family, _photo(rng, SURFACE_PHOTOS, rng.uniform(1.5, 3.0)),
                                  _platform(rng, lambda length: _top(rng, length))))
    if family == "landing_none_photo":
        return _landing(rng, family, _photo(rng, SURFACE_PHOTOS, rng.uniform(1.5, 3.0)), None)
    if family in ("landing_moving_cart", "landing_deck"):
        deck = family == "landing_deck"
        scene = _landing(rng, family, _photo(rng, SURFACE_PHOTOS, rng.uniform(1.5, 3.0)),
                         _platform(rng, lambda length: _top(rng, length)))
        return _moving_platform(rng, scene, (0.2, 0.5) if deck else (0.5, 1.0), deck)
    if family == "ingress_photo":
        return _ingress(rng, family, _opening(rng))
    if family == "ingress_smooth_wall":
        scene = _ingress(rng, family, _opening(rng))
        scene["wall"]["texture"] = _photo(rng, SMOOTH_PHOTOS, rng.uniform(2.5, 4.0))
        scene["wall"]["room_texture"] = _photo(rng, BUSY_PHOTOS, rng.uniform(1.0, 2.5))
        return scene
    assert family == "ingress_solid_photo"
    return _ingress(rng, family, None)


def mission_of(family):
    return "ingress" if family.startswith("ingress") else "landing"
