"""Run the ASAM OpenDRIVE checker on several files in one process of its own environment.

Not part of flyover's API: :mod:`flyover.opendrive.qc` runs this file *by path*
with the checker environment's python (``.venv-qc``), which has
``asam-qc-opendrive`` but not flyover, so this module imports only the
standard library and the checker's own packages (inside :func:`main`)::

    .venv-qc/bin/python _qc_driver.py JOBS.json

``JOBS.json``::

    {"configs": ["a/config.xml", ...],          # the checker's own config files
     "excluded_by": [null, "1.8.0", ...],       # per config (optional): see below
     "xsd11": [["OpenDRIVE_Core.xsd", "b.xodr"], ...]}

``excluded_by`` ``V`` runs, of the version-bound checkers, only those that do
*not* apply to OpenDRIVE ``V`` (the bundle's own ``check_version`` decides);
the checkers the others take as preconditions (the basic ones and the schema
check against the file's own version) run as always. flyover uses it on an
interchange's rendition in the other version, which differs from the file in
the declared version alone: every checker that applies to the file's version
has run on the file itself, with the same content.

For every config this does what ``python -m qc_opendrive -c config.xml``
does (:func:`qc_opendrive.main.main`): a fresh ``Configuration`` and
``Result``, the bundle's ``run_checks``, the result file (``.xqar``) at the
config's ``resultFile``. The checker's startup (imports, ~0.7 s) is paid once
per process, and an XSD 1.1 schema (OpenDRIVE 1.8, built by ``xmlschema``,
~0.5 s) once per schema file: the bundle's ``valid_schema`` checker gets a
memoizing stand-in for ``xmlschema.XMLSchema11`` (same schema, same
validation, built once). ``xsd11`` jobs validate a file against an XSD 1.1
schema the same way (flyover's own ``xsd`` check of 1.8 files).

XSD 1.1 identity constraints (OpenDRIVE 1.8 declares 31 ``xs:key``/``keyref``
on ``OpenDRIVE``) cost most of a file's validation: for every element a key
selects, ``xmlschema`` evaluates the field's XPath, and ``elementpath``
re-annotates the *whole document* with schema types first (its
``apply_schema`` skips only when the node already carries the same proxy
object, and each field brings a proxy of its own). A whole-document
annotation is a function of the document and the schema alone (proxies
without a base element, on a fully valid schema), so
:func:`_share_document_annotations` skips one that repeats the annotation
already in place for the same document and schema; anything else that
touches the annotations (another schema, a base element, assertions,
``clear_types``) runs as before and forgets it. Same errors, less than half
the CPU (``tests/test_opendrive_tools.py`` validates broken files both ways).
``"share_annotations": false`` in ``JOBS.json`` turns it off.

Prints one JSON object on stdout: per config ``{"seconds", "error"}``, per
xsd11 job ``{"seconds", "errors", "error"}`` (``errors``: ``"line N:
reason"``), and ``startup_seconds``. A job that raises is reported with its
error; the other jobs still run.
"""

import json
import logging
import sys
import time


class _MemoXmlschema:
    """Stand-in for the ``xmlschema`` module: ``XMLSchema11`` built once per schema file."""

    def __init__(self, module):
        self._module = module
        self._schemas = {}

    def __getattr__(self, name):
        return getattr(self._module, name)

    def XMLSchema11(self, source, *args, **kwargs):  # noqa: N802 - the module's own name
        if args or kwargs or not isinstance(source, str):
            return self._module.XMLSchema11(source, *args, **kwargs)
        if source not in self._schemas:
            self._schemas[source] = self._module.XMLSchema11(source)
        return self._schemas[source]


class _Sink:
    """A result that forgets what it is told (to ask ``check_version`` without recording)."""

    def __getattr__(self, name):
        return lambda *args, **kwargs: None


def _only_excluded_by(main, version):
    """``main.execute_checker`` that runs a version-bound checker only when ``version`` is
    outside its applicable versions."""
    import types

    from qc_opendrive.basic_preconditions import CHECKER_PRECONDITIONS

    run = main.execute_checker
    probe = types.SimpleNamespace(schema_version=version, result=_Sink())

    def execute_checker(checker, checker_data, version_required=True):
        if version_required and checker.CHECKER_ID not in CHECKER_PRECONDITIONS and \
                main.check_version(checker, probe):
            return None  # applies to ``version``: it ran on the file of that version
        return run(checker, checker_data, version_required)

    return execute_checker


def _share_document_annotations():
    """Skip ``elementpath``'s whole-document type annotation when it would repeat the one in place."""
    from elementpath import xpath_nodes as nodes

    state = {"root": None, "schema": None}  # the annotation in place: document root and XSD schema

    def forget():
        state["root"] = state["schema"] = None

    apply = nodes.EtreeElementNode.apply_schema

    def apply_schema(self, proxy):
        whole = (proxy.base_element is None and proxy.is_fully_valid()
                 and not proxy.is_assertion_based())
        if whole:
            root = self
            while isinstance(root.parent, nodes.EtreeElementNode):
                root = root.parent
            if state["root"] is root and state["schema"] is proxy.schema:
                self.schema = proxy  # what the full pass leaves on the node it started from
                return
        forget()
        apply(self, proxy)
        if whole:
            state["root"], state["schema"] = root, proxy.schema

    def forgetting(fn):
        def wrapper(*args, **kwargs):
            forget()
            return fn(*args, **kwargs)
        return wrapper

    nodes.EtreeElementNode.apply_schema = apply_schema
    for cls, name in ((nodes.EtreeElementNode, "clear_types"), (nodes.DocumentNode, "apply_schema"),
                      (nodes.DocumentNode, "clear_types"), (nodes.AttributeNode, "apply_schema")):
        setattr(cls, name, forgetting(getattr(cls, name)))


def _run_config(path, bundle, excluded_by=None):
    from qc_baselib import Configuration, Result

    main, constants = bundle
    config = Configuration()
    config.load_from_file(xml_file_path=path)
    result = Result()
    result.register_checker_bundle(name=constants.BUNDLE_NAME, description="OpenDrive checker bundle",
                                   version=constants.BUNDLE_VERSION, summary="")
    result.set_result_version(version=constants.BUNDLE_VERSION)
    execute = main.execute_checker
    if excluded_by:
        main.execute_checker = _only_excluded_by(main, excluded_by)
    try:
        main.run_checks(config, result)
    finally:
        main.execute_checker = execute
    result.copy_param_from_config(config)
    result.write_to_file(config.get_checker_bundle_param(checker_bundle_name=constants.BUNDLE_NAME,
                                                         param_name="resultFile"),
                         generate_summary=True)


def _xsd11_errors(schema_path, xodr, memo):
    from lxml import etree

    schema = memo.XMLSchema11(schema_path)
    return [f"line {e.sourceline}: {e.reason}" for e in schema.iter_errors(etree.parse(xodr))]


def _timed(fn, *args):
    t0 = time.perf_counter()
    try:
        value, error = fn(*args), None
    except Exception as exc:  # noqa: BLE001 - reported per job; the other jobs still run
        value, error = None, f"{type(exc).__name__}: {exc}"
    return value, error, round(time.perf_counter() - t0, 4)


def main(argv):
    t0 = time.perf_counter()
    with open(argv[1], encoding="utf-8") as fh:
        jobs = json.load(fh)
    import xmlschema
    from qc_opendrive import constants
    from qc_opendrive import main as qc_main
    from qc_opendrive.checks.schema import valid_schema

    logging.getLogger().setLevel(logging.WARNING)  # the bundle logs every check at INFO
    if jobs.get("share_annotations", True):
        _share_document_annotations()
    memo = _MemoXmlschema(xmlschema)
    valid_schema.xmlschema = memo
    out = {"startup_seconds": round(time.perf_counter() - t0, 4), "configs": [], "xsd11": []}
    configs = jobs.get("configs", [])
    for path, excluded_by in zip(configs, jobs.get("excluded_by") or [None] * len(configs)):
        _, error, seconds = _timed(_run_config, path, (qc_main, constants), excluded_by)
        out["configs"].append({"seconds": seconds, "error": error})
    for schema_path, xodr in jobs.get("xsd11", []):
        errors, error, seconds = _timed(_xsd11_errors, schema_path, xodr, memo)
        out["xsd11"].append({"seconds": seconds, "errors": errors or [], "error": error})
    sys.stdout.write(json.dumps(out) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
