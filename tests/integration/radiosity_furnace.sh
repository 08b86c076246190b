# Radiosity white furnace, end to end: in a closed box whose walls all
# reflect 0.5 and emit 1.0, radiosity (in radiance units) is
# E / (1 - rho) = 2.0 everywhere, within 1%: in every pixel of the camera
# image, with 2MF and with 2MCE.
. "$(dirname "$0")/lib.sh"
cat >"$TMP/furnace.json" <<SCENE
{
  "camera": {"position": [-0.3, 0.1, 0.2], "look_at": [0.9, -0.2, 0.5], "fov_y": 110},
  "materials": {"wall": {"diffuse": [0.5, 0.5, 0.5], "emission": [1, 1, 1]}},
  "objects": [{"name": "room", "material": "wall", "box": {"size": [3, 1, 2], "inward": true}}]
}
SCENE
for kind in 2mf 2mce; do
    write_job "$TMP/job-$kind.json" <<JOB
{
  "scene": "furnace.json",
  "method": "radiosity",
  "image": {"width": 16, "height": 12},
  "radiosity": {"factorization": "$kind", "patches": 48, "levels": 2, "image_spp": 2},
  "outputs": {"exr": "furnace.exr", "report": "furnace.json"}
}
JOB
    "$GI" render "$TMP/job-$kind.json" --workers 2 --out "$TMP/$kind" --progress none ||
        fail "render ($kind)"
    "$IMGTOOL" check-const "$TMP/$kind/furnace.exr" 2.0 0.01 || fail "$kind: not 2.0 everywhere"
    grep -q '"escaped_fraction":	0,' "$TMP/$kind/furnace.json" || fail "$kind: rays escaped a closed box"
done
echo ok
