#!/usr/bin/python3
"""docs/NODES.md names every parameter the nodes and the config loaders read.

Scans every .cpp/.h under src/<package>/src and src/<package>/include (cores, nodes and their
headers; not tests or benchmarks) for parameter reads:
  - YAML keys read through ehc_common::ConfigNode: get, require, child, childOrEmpty, getVector,
    requireVector, getStrings, listSize, element, has, ignore, getPath, requirePath, getInRange
    with a literal key; a lambda or a
    function that takes the key and passes it on (`auto get = [&](const char* key, ...) {
    n.get(key, ...) }`, a NodeHandle helper taking the name); a range-for over a list of literal
    keys passed on the same way;
  - private ROS parameters: ehc_common::NodeParams get, getOptional, getParsed, getInRange,
    requireText, getList, has; NodeHandle param, getParam, hasParam, searchParam, getParamCached
    and ros::param::get / param / has (a leading `~` is dropped).
Calls on a CommandLine (the CLI tools' options) are not parameters. A key counts as documented
when it appears as a word inside a `code span` of docs/NODES.md (`controller.rate`,
`_robot:=name` and `| `rate` |` all name `rate`). The scan does not depend on which file a
loader lives in, and it fails if it finds no key at all.

  /usr/bin/python3 -m pytest src/ehc_bringup/test/test_nodes_doc.py
  /usr/bin/python3 src/ehc_bringup/test/test_nodes_doc.py [--list]   (the keys and where they are read)
"""
import glob
import os
import re
import sys

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", ".."))
NODES_MD = os.path.join(ROOT, "docs", "NODES.md")

CONFIG_METHODS = ("get", "require", "child", "childOrEmpty", "getVector", "requireVector", "getStrings",
                  "listSize", "element", "has", "ignore", "getPath", "requirePath", "getInRange")
# ehc_common::NodeParams (the nodes' private parameters) beside get / has / getInRange above.
NODE_PARAM_METHODS = ("getOptional", "getParsed", "requireText", "getList")
ROS_METHODS = ("param", "getParam", "hasParam", "searchParam", "getParamCached")
METHODS = CONFIG_METHODS + NODE_PARAM_METHODS + ROS_METHODS
KEY = r'"~?([A-Za-z_][A-Za-z0-9_]*)"'
TEMPLATE = r'(?:<[^;(){}]*?>)?'
# receiver.method<T>("key"  /  receiver->method("key"  /  call(...).method("key"
DIRECT = re.compile(r'(\w+|\))\s*(?:\.|->)\s*(%s)\s*%s\s*\(\s*%s' % ("|".join(METHODS), TEMPLATE, KEY))
ROS_PARAM_NS = re.compile(r'ros::param::(?:get|param|has|getCached|search)\s*%s\s*\(\s*%s' % (TEMPLATE, KEY))
COMMAND_LINE_VAR = re.compile(r'\bCommandLine\s+(\w+)\s*[({]')
LAMBDA = re.compile(r'\bauto\s+(\w+)\s*=\s*\[[^\]]*\]\s*\(\s*(?:const\s+)?(?:char\s*\*|std::string\s*&?)\s*(\w+)')
# A function definition: name, parameter list, then its body.
FUNCTION = re.compile(r'\b(\w+)\s*\(([^()]*)\)\s*(?:const\s*)?(?:noexcept\s*)?\{')
KEY_PARAM = re.compile(r'(?:const\s+)?(?:char\s*\*|std::string\s*&?)\s*(\w+)\s*(?:=[^,]*)?$')
RANGE_FOR = re.compile(r'\bfor\s*\(\s*(?:const\s+)?(?:char\s*\*|std::string\s*&?|auto\s*&?|auto\s*\*)\s*(\w+)\s*:\s*'
                       r'\{([^{}]*)\}\s*\)')


def strip_comments(text):
    """C++ text with comments blanked (string literals kept, line numbers kept)."""
    out, i, n = [], 0, len(text)
    while i < n:
        c = text[i]
        if c == '"' or c == "'":
            j = i + 1
            while j < n and text[j] != c:
                j += 2 if text[j] == "\\" else 1
            out.append(text[i:j + 1])
            i = j + 1
        elif text.startswith("//", i):
            j = text.find("\n", i)
            i = n if j < 0 else j
        elif text.startswith("/*", i):
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append("\n" * text.count("\n", i, j))
            i = j
        else:
            out.append(c)
            i += 1
    return "".join(out)


def block_after(text, pos, limit=1500):
    """The text of the brace block (or single statement) that starts at or after `pos`."""
    brace = text.find("{", pos)
    semi = text.find(";", pos)
    if brace < 0 or (0 <= semi < brace):
        return text[pos:semi + 1 if semi >= 0 else pos + limit]
    depth = 0
    for j in range(brace, min(len(text), brace + 20 * limit)):
        depth += text[j] == "{"
        depth -= text[j] == "}"
        if depth == 0:
            return text[pos:j + 1]
    return text[pos:pos + limit]


def passes_on(body, var):
    """True if `var` is passed as the key of a ConfigNode / NodeHandle read inside `body`."""
    return re.search(r'(?:\.|->)\s*(?:%s)\s*%s\s*\(\s*%s\b' % ("|".join(METHODS), TEMPLATE, re.escape(var)), body) \
        is not None


def scan_text(text):
    """[(key, line)] of the parameter reads in one C++ source text."""
    text = strip_comments(text)
    line = lambda pos: text.count("\n", 0, pos) + 1  # noqa: E731
    cli_vars = set(COMMAND_LINE_VAR.findall(text))
    found = []
    for m in DIRECT.finditer(text):
        if m.group(1) not in cli_vars:
            found.append((m.group(3), line(m.start())))
    for m in ROS_PARAM_NS.finditer(text):
        found.append((m.group(1), line(m.start())))
    # Wrappers that take the key and pass it on: lambdas and functions.
    wrappers = set()
    for m in LAMBDA.finditer(text):
        if passes_on(block_after(text, m.end()), m.group(2)):
            wrappers.add(m.group(1))
    for m in FUNCTION.finditer(text):
        if m.group(1) in ("if", "for", "while", "switch", "catch"):
            continue
        body = block_after(text, m.end() - 1)
        for param in m.group(2).split(","):
            k = KEY_PARAM.search(param.strip())
            if k and passes_on(body, k.group(1)):
                wrappers.add(m.group(1))
    for name in wrappers:
        for m in re.finditer(r'\b%s\s*\((?:[^()"]*,\s*)?%s' % (re.escape(name), KEY), text):
            found.append((m.group(1), line(m.start())))
    # for (const char* k : {"a", "b"}) n.get(k, ...)
    for m in RANGE_FOR.finditer(text):
        if passes_on(block_after(text, m.end()), m.group(1)):
            for k in re.findall(KEY, m.group(2)):
                found.append((k, line(m.start())))
    return found


def source_files(root=ROOT):
    files = []
    for pattern in ("src/*/src/**/*.cpp", "src/*/src/**/*.h", "src/*/include/**/*.h"):
        files += glob.glob(os.path.join(root, pattern), recursive=True)
    return sorted(set(files))


def scan(root=ROOT):
    """{key: [file:line, ...]} over every source file."""
    keys = {}
    for path in source_files(root):
        with open(path, errors="replace") as f:
            for key, ln in scan_text(f.read()):
                keys.setdefault(key, []).append("%s:%d" % (os.path.relpath(path, root), ln))
    return keys


def documented_words(markdown):
    """Every word inside a `code span` of the markdown text (leading underscores dropped)."""
    words = set()
    for span in re.findall(r"`([^`\n]+)`", markdown):
        for w in re.findall(r"[A-Za-z0-9_]+", span):
            words.add(w.lstrip("_"))
    return words


# ------------------------------------------------------------------------------ tests
def test_scanner_finds_every_kind_of_read():
    src = '''
      // n.get("commented_out", 1)
      p.a = n.get<double>("plain", p.a);
      p.b = n.childOrEmpty("section").require<int>(
          "multi_line");
      const ehc_common::CommandLine cli(argc, argv, {"x"});
      if (cli.has("not_a_parameter")) {}
      pnh.param<std::string>("ack_topic", topic_, "");
      ros::param::get("~private_name", v);
      auto get = [&](const char* key, double& field) { field = n.get<double>(key, field); };
      get("through_lambda", p.c);
      for (const char* k : {"loop_a", "loop_b"}) if (n.has(k)) n.fail(k, "x");
      std::string robotFileField(const ehc_common::ConfigNode& node, const std::string& key) {
        return node.require<std::string>(key);
      }
      robotFileField(n, "through_function");
      template <class T> void override(const ros::NodeHandle& pnh, const std::string& name, T* value) {
        if (pnh.hasParam(name)) pnh.getParam(name, *value);
      }
      override(pnh, "node_override", &p.x);
      p.mode = params.getParsed<ControlMode>("node_param_parsed", controlModeFromString).value_or(p.mode);
      const std::string cfg = params.requireText("node_param_text", "<x.yaml>");
      p.path = n.getPath("config_path", p.path);
      void unrelated(const std::string& text) { log(text); }
      unrelated("not_a_key_either");
    '''
    keys = {k for k, _ in scan_text(src)}
    assert keys == {"plain", "section", "multi_line", "ack_topic", "private_name", "through_lambda", "loop_a",
                    "loop_b", "through_function", "node_override", "node_param_parsed", "node_param_text",
                    "config_path"}


def test_documented_words_are_code_spans_only():
    words = documented_words("rate in prose, `node.wall_timeout`, `_robot:=name` | `mode` |")
    assert {"node", "wall_timeout", "robot", "name", "mode"} <= words
    assert "rate" not in words


def test_every_parameter_is_in_nodes_md():
    keys = scan()
    print("[nodes doc] %d parameter keys read in %d source files" % (len(keys), len(source_files())))
    assert keys, "no parameter read found under src/*/src and src/*/include: the scanner is broken"
    assert os.path.exists(NODES_MD), "docs/NODES.md is missing"
    with open(NODES_MD) as f:
        words = documented_words(f.read())
    missing = sorted(k for k in keys if k not in words)
    assert not missing, "docs/NODES.md does not name %d of %d parameter keys:\n%s" % (
        len(missing), len(keys), "\n".join("  %s (read at %s)" % (k, ", ".join(keys[k][:3])) for k in missing))


if __name__ == "__main__":
    found = scan()
    if "--list" in sys.argv:
        for k in sorted(found):
            print("%-32s %s" % (k, " ".join(found[k])))
    print("%d keys" % len(found))
