"""Wrap parameters as keyword arguments, a dict, or a JSON/YAML file, in the form of the API's
WrapParameters message: the same files as the command line's `vdbwrap wrap --params`.

Field names as in jobs.proto (snake_case; lowerCamelCase also works); enums by name
("VOLUME_INSIDE") or the short "inside"; shapes "SHAPE_BOX" or "box". A few shorthands of
Python: a Point may be a sequence (x, y, z), a Size a string "1%" (percent of the diagonal) or
a number (model units).
"""
import difflib
import json
import os

from google.protobuf import json_format

from vdbwrap.errors import ParameterError
from vdbwrap.v1 import jobs_pb2 as pb

_MAX_DEPTH = 32  # a WrapParameters message is a few levels deep


def load_file(path):
    """A parameter file as a dict: .yaml / .yml are YAML, anything else JSON."""
    path = os.fspath(path)
    try:
        with open(path, encoding="utf-8") as f:
            text = f.read()
    except OSError as e:
        raise ParameterError("%s: cannot read the parameter file (%s)" % (path, e.strerror)) from None
    except UnicodeDecodeError:
        raise ParameterError("%s: the parameter file is not UTF-8 text" % path) from None
    try:
        if path.lower().endswith((".yaml", ".yml")):
            import yaml  # Debian: python3-yaml

            data = yaml.safe_load(text)
        else:
            data = json.loads(text)
    except ValueError as e:
        raise ParameterError("%s: not valid JSON: %s" % (path, e)) from None
    except Exception as e:  # yaml.YAMLError; yaml is imported lazily
        raise ParameterError("%s: not valid YAML: %s" % (path, e)) from None
    if data is None:
        data = {}
    if not isinstance(data, dict):
        raise ParameterError("%s: expected a mapping of parameter names to values (the WrapParameters message)" % path)
    return _unnest(data)


def _unnest(data):
    # A file may also nest the parameters under "params" (as in a JobSpec).
    if len(data) == 1 and isinstance(data.get("params"), dict):
        return dict(data["params"])
    return dict(data)


def _field(descriptor, name, where):
    """The field of `descriptor` called `name` (or its lowerCamelCase); else a ParameterError
    naming the closest valid name."""
    by_name = {}
    for f in descriptor.fields:
        by_name[f.name] = f
        by_name[f.json_name] = f
    if not isinstance(name, str):
        raise ParameterError("%s: parameter names are strings, not %r" % (where, name))
    if name in by_name:
        return by_name[name]
    valid = [f.name for f in descriptor.fields]
    close = difflib.get_close_matches(name, valid, n=1, cutoff=0.5)
    if not close:  # a camelCase spelling is compared as snake_case
        snake = "".join("_" + c.lower() if c.isupper() else c for c in name)
        close = difflib.get_close_matches(snake, valid, n=1, cutoff=0.5)
    label = "unknown parameter %r" % name if where == "WrapParameters" else "unknown field %r in %s" % (name, where)
    if close:
        raise ParameterError("%s; did you mean %r?" % (label, close[0]), suggestion=close[0])
    raise ParameterError("%s; valid names: %s" % (label, ", ".join(valid)))


def _enum(field, value, path):
    if not isinstance(value, str):
        return value
    names = [v.name for v in field.enum_type.values]
    if value in names:
        return value
    prefix = names[0][: names[0].rfind("_UNSPECIFIED") + 1]  # "VOLUME_", "SHAPE_"
    full = prefix + value.strip().upper().replace(" ", "_").replace("-", "_")
    if full in names:
        return full
    short = [n[len(prefix):].lower() for n in names if not n.endswith("_UNSPECIFIED")]
    close = difflib.get_close_matches(value.lower(), short, n=1, cutoff=0.5)
    hint = "; did you mean %r?" % close[0] if close else ""
    raise ParameterError("%s: unknown value %r (one of %s)%s" % (path, value, ", ".join(short), hint),
                         suggestion=close[0] if close else None)


def _message(descriptor, value, where, depth):
    """value as the JSON form of `descriptor`, with its names checked and shorthands expanded."""
    if depth > _MAX_DEPTH:
        raise ParameterError("%s: nested more than %d levels deep" % (where, _MAX_DEPTH))
    if descriptor.name == "Point" and isinstance(value, (list, tuple)):
        if len(value) != 3:
            raise ParameterError("%s: a point has 3 coordinates, got %d" % (where, len(value)))
        value = dict(zip("xyz", value))
    elif descriptor.name == "Size" and isinstance(value, str) and value.strip().endswith("%"):
        try:
            value = {"percent": float(value.strip()[:-1])}
        except ValueError:
            raise ParameterError("%s: not a size: %r (e.g. \"1%%\" or a length in model units)" % (where, value)) from None
    elif descriptor.name == "Size" and isinstance(value, (int, float)) and not isinstance(value, bool):
        value = {"model_units": value}
    if not isinstance(value, dict):
        raise ParameterError("%s: expected a mapping (a %s message), got %r" % (where, descriptor.name, value))
    out = {}
    for name, item in value.items():
        field = _field(descriptor, name, where)
        path = "%s.%s" % (where, field.name) if where != "WrapParameters" else field.name
        repeated = field.label == field.LABEL_REPEATED
        items = item if repeated and isinstance(item, (list, tuple)) else None
        if repeated and items is None:
            raise ParameterError("%s: expected a list, got %r" % (path, item))
        if field.message_type is not None:
            if repeated:
                item = [_message(field.message_type, v, "%s[%d]" % (path, i), depth + 1) for i, v in enumerate(items)]
            else:
                item = _message(field.message_type, item, path, depth + 1)
        elif field.enum_type is not None:
            item = [_enum(field, v, path) for v in items] if repeated else _enum(field, item, path)
        out[field.name] = item
    return out


def wrap_parameters(params=None, **kwargs):
    """A WrapParameters message from a dict, a file path, a WrapParameters message and/or
    keyword arguments (which override the others). Raises ParameterError naming what is wrong."""
    merged = {}
    if isinstance(params, pb.WrapParameters):
        merged = json_format.MessageToDict(params, preserving_proto_field_name=True)
    elif isinstance(params, dict):
        merged = _unnest(params)
    elif isinstance(params, (str, os.PathLike)):
        merged = load_file(params)
    elif params is not None:
        raise ParameterError("params: expected a dict, a file path or a WrapParameters message, got %s"
                             % type(params).__name__)
    for name in kwargs:  # a keyword argument replaces the file's choice in the same oneof
        field = pb.WrapParameters.DESCRIPTOR.fields_by_name.get(name)
        if field is not None and field.containing_oneof is not None:
            for other in field.containing_oneof.fields:
                merged.pop(other.name, None)
                merged.pop(other.json_name, None)
    merged.update(kwargs)
    checked = _message(pb.WrapParameters.DESCRIPTOR, merged, "WrapParameters", 0)
    try:
        return json_format.ParseDict(checked, pb.WrapParameters())
    except json_format.ParseError as e:
        raise ParameterError("bad wrap parameters: %s" % e) from None
