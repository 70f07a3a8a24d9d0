"""A Mitsuba 3 shape's or sensor's to_world as a 4x4 matrix (nested lists), for the validation tools
that read scene XML without a renderer (coplanar_faces.py, rect_light_closed_form.py). Python
standard library only. Malformed input raises ValueError with a message naming the place and field;
the caller prefixes its own name and exits."""


def matmul(a, b):
    return [[sum(a[r][k] * b[k][c] for k in range(4)) for c in range(4)] for r in range(4)]


def transform_step(node, where):
    """One child of <transform> as a 4x4 matrix: matrix, translate or scale (Mitsuba's attributes),
    or None for a kind this module does not read."""
    def number(name, default):
        try:
            return float(node.get(name, default))
        except ValueError:
            raise ValueError("%s: field %s: '%s' is not a number" % (where, name, node.get(name))) from None
    if node.tag == "matrix":
        try:
            m = [float(v) for v in (node.get("value") or "").replace(",", " ").split()]
        except ValueError:
            m = []
        if len(m) != 16:
            raise ValueError("%s: field to_world: <matrix value> needs 16 numbers" % where)
        return [m[0:4], m[4:8], m[8:12], m[12:16]]
    if node.tag == "translate":
        return [[1, 0, 0, number("x", 0)], [0, 1, 0, number("y", 0)], [0, 0, 1, number("z", 0)], [0, 0, 0, 1]]
    if node.tag == "scale":
        v = number("value", 1)
        return [[number("x", v), 0, 0, 0], [0, number("y", v), 0, 0], [0, 0, number("z", v), 0], [0, 0, 0, 1]]
    return None


def to_world(element, where):
    """The element's 4x4 to_world (identity without one), or None when it uses a transform this
    module does not read (rotate, lookat)."""
    M = [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]
    t = element.find("transform[@name='to_world']")
    for node in ([] if t is None else list(t)):
        step = transform_step(node, where)
        if step is None:
            return None
        M = matmul(step, M)  # Mitsuba applies a transform's children in order
    return M
