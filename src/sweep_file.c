/* The sweep file's reader (sweep_file.h). A value of any shape (a number, a list, a list of
 * lists or maps, for keys that other parts of the scenario may add) travels to the scenario
 * loader as a `--set key=value` override with the value written back as YAML flow text, so the
 * sweep needs to know nothing of a key's type: the loader checks it, and its messages about an
 * override are moved to the override's place in the sweep file. */
#include "sweep_file.h"

#include <ctype.h>
#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "yaml_tree.h"

/* YAML flow text of a node, cut at SD_SWEEP_MAX_TEXT (over set). */
typedef struct {
    char buf[SD_SWEEP_MAX_TEXT];
    size_t len;
    int over;
} flow_text;

static void put(flow_text *t, const char *s, size_t n)
{
    if (t->over || t->len + n >= sizeof t->buf) {
        t->over = 1;
        return;
    }
    memcpy(t->buf + t->len, s, n);
    t->len += n;
    t->buf[t->len] = '\0';
}

/* A scalar that reads back as itself without quotes, in flow context and as a whole document:
 * numbers, words, paths. Anything else is double-quoted. */
static int plain_ok(const char *v)
{
    const size_t n = strlen(v);
    if (n == 0 || v[0] == ' ' || v[n - 1] == ' ') return 0;
    if (!(isalnum((unsigned char)v[0]) || v[0] == '.' || v[0] == '+' ||
          (v[0] == '-' && (isdigit((unsigned char)v[1]) || v[1] == '.'))))
        return 0;
    for (const char *c = v; *c; c++)
        if (!isalnum((unsigned char)*c) && !strchr("._+-/ ", *c)) return 0;
    return 1;
}

static void put_scalar(flow_text *t, const char *v)
{
    if (plain_ok(v)) {
        put(t, v, strlen(v));
        return;
    }
    put(t, "\"", 1);
    for (const unsigned char *c = (const unsigned char *)v; *c; c++) {
        char esc[8];
        if (*c == '"' || *c == '\\') {
            esc[0] = '\\';
            esc[1] = (char)*c;
            put(t, esc, 2);
        } else if (*c < 0x20 || *c == 0x7f) {
            snprintf(esc, sizeof esc, "\\x%02x", *c);
            put(t, esc, 4);
        } else
            put(t, (const char *)c, 1);
    }
    put(t, "\"", 1);
}

/* (the reader nests collections at most SD_YAML_MAX_DEPTH deep, which bounds the recursion) */
static void put_node(flow_text *t, const sd_ynode *n)
{
    if (n->kind == SD_Y_SCALAR) {
        put_scalar(t, n->value);
        return;
    }
    put(t, n->kind == SD_Y_SEQ ? "[" : "{", 1);
    for (int i = 0; i < n->n && !t->over; i++) {
        if (i) put(t, ", ", 2);
        if (n->kind == SD_Y_MAP) {
            put_scalar(t, n->keys[i]);
            put(t, ": ", 2);
        }
        put_node(t, n->items[i]);
    }
    put(t, n->kind == SD_Y_SEQ ? "]" : "}", 1);
}

/* o := "key=<v as flow text>"; 0, or -1 with the error reported */
static int make_override(sd_sweep_override *o, const char *where, const char *key, const sd_ynode *v, const char *path,
                         FILE *err)
{
    flow_text *t = malloc(sizeof *t);
    if (!t) {
        fprintf(err, "%s: out of memory\n", path);
        return -1;
    }
    t->len = 0;
    t->over = 0;
    t->buf[0] = '\0';
    put(t, key, strlen(key));
    put(t, "=", 1);
    put_node(t, v);
    if (t->over) {
        fprintf(err, "%s:%d:%d: %s: a value longer than %d characters in YAML\n", path, v->line, v->col, where,
                SD_SWEEP_MAX_TEXT - 2 - (int)strlen(key));
        free(t);
        return -1;
    }
    o->text = strdup(t->buf);
    o->line = v->line;
    o->col = v->col;
    free(t);
    if (!o->text) {
        fprintf(err, "%s: out of memory\n", path);
        return -1;
    }
    return 0;
}

/* A name that is safe as a CSV column and value and in a directory name. */
static int safe_name(const char *s)
{
    const size_t n = strlen(s);
    if (n == 0 || n >= SD_SWEEP_MAX_NAME) return 0;
    for (; *s; s++)
        if (!isalnum((unsigned char)*s) && !strchr("._+-", *s)) return 0;
    return 1;
}

static int is_scenario_key(const char *k)
{
    for (int i = 0; i < sd_scenario_param_count(); i++)
        if (!strcmp(k, sd_scenario_param_key(i))) return 1;
    return 0;
}

/* results.csv's own columns, which a set of variants may not be called */
static int reserved_column(const char *k)
{
    static const char *const cols[] = {
        "case",         "seed",        "p_v",         "p_v_logs",         "k_w",    "l_v_d_max", "v_held_m3",
        "v_channel_m3", "v_passed_m3", "capture_end", "peak_dam_force_N", "passed", "wall_s",    "capture_limit_s",
        "flow_wall_s",  "branched",    "state_hash"};
    for (size_t i = 0; i < sizeof cols / sizeof cols[0]; i++)
        if (!strcmp(k, cols[i])) return 1;
    return !strncmp(k, "p_v_class", 9);
}

/* does the override set key? */
static int sets_key(const sd_sweep_override *o, const char *key)
{
    const size_t n = strlen(key);
    return !strncmp(o->text, key, n) && o->text[n] == '=';
}

/* the override of axis a that sets key, or NULL */
static const sd_sweep_override *axis_sets(const sd_sweep_axis *a, const char *key)
{
    for (int v = 0; v < a->n_val; v++)
        for (int k = 0; k < a->val[v].n; k++)
            if (sets_key(&a->val[v].set[k], key)) return &a->val[v].set[k];
    return NULL;
}

/* the key an override sets, into buf */
static const char *override_key(const sd_sweep_override *o, char *buf, size_t n)
{
    const char *eq = strchr(o->text, '=');
    snprintf(buf, n, "%.*s", (int)(eq ? eq - o->text : 0), o->text);
    return buf;
}

/* One axis of `vary`: a key with a list of values, or a name with a mapping of variants. */
static int load_axis(sd_sweep_file *d, const sd_ynode *vary, int j, FILE *err)
{
    const char *path = d->path, *name = vary->keys[j];
    const sd_ynode *node = vary->items[j];
    sd_sweep_axis *a = &d->axis[d->n_axes];
    if (d->n_axes == SD_SWEEP_MAX_AXES) {
        fprintf(err, "%s:%d:%d: vary: more than %d keys or sets of variants\n", path, vary->key_line[j],
                vary->key_col[j], SD_SWEEP_MAX_AXES);
        return -1;
    }
    if (strlen(name) >= sizeof a->name) {
        fprintf(err, "%s:%d:%d: vary: a key of %zu characters (at most %zu)\n", path, vary->key_line[j],
                vary->key_col[j], strlen(name), sizeof a->name - 1);
        return -1;
    }
    if ((node->kind != SD_Y_SEQ && node->kind != SD_Y_MAP) || node->n < 1 || node->n > SD_SWEEP_MAX_VALUES) {
        fprintf(err,
                "%s:%d:%d: vary.%s: expected a list of 1..%d values, or a mapping of 1..%d named variants "
                "(name: {key: value, ...})\n",
                path, node->line, node->col, name, SD_SWEEP_MAX_VALUES, SD_SWEEP_MAX_VALUES);
        return -1;
    }
    snprintf(a->name, sizeof a->name, "%s", name);
    d->n_axes++;
    a->variants = node->kind == SD_Y_MAP;
    a->capture = 1;
    if (!a->variants) {
        for (int q = 0; q < node->n; q++) {
            const sd_ynode *v = node->items[q];
            sd_sweep_value *val = &a->val[a->n_val++];
            char where[160];
            snprintf(where, sizeof where, "vary.%s", name);
            if (make_override(&val->set[0], where, name, v, path, err)) return -1;
            val->n = 1;
            val->label = strdup(v->kind == SD_Y_SCALAR ? v->value : strchr(val->set[0].text, '=') + 1);
            if (!val->label) return -1;
        }
        a->capture = sd_scenario_is_capture_key(name);
        return 0;
    }
    if (is_scenario_key(name) || !safe_name(name) || reserved_column(name)) {
        fprintf(err,
                "%s:%d:%d: vary.%s: %s; named variants go under a name of your own, of letters, digits and ._+- "
                "(e.g. layout: {narrow: {dam.l_h: 0.04}, wide: {dam.l_h: 0.06}})\n",
                path, vary->key_line[j], vary->key_col[j], name,
                is_scenario_key(name)   ? "a scenario key takes a list of values ([a, b, ...])"
                : reserved_column(name) ? "the name of a results.csv column"
                                        : "not a name for a set of variants");
        return -1;
    }
    for (int q = 0; q < node->n; q++) {
        const sd_ynode *v = node->items[q];
        const char *vname = node->keys[q];
        sd_sweep_value *val = &a->val[a->n_val++];
        if (!safe_name(vname)) {
            fprintf(err, "%s:%d:%d: vary.%s: '%s': a variant's name is 1 to %d letters, digits and ._+-\n", path,
                    node->key_line[q], node->key_col[q], name, vname, SD_SWEEP_MAX_NAME - 1);
            return -1;
        }
        if (v->kind != SD_Y_MAP || v->n > SD_SWEEP_MAX_KEYS) {
            fprintf(err, "%s:%d:%d: vary.%s.%s: expected a mapping of at most %d scenario keys to values\n", path,
                    v->line, v->col, name, vname, SD_SWEEP_MAX_KEYS);
            return -1;
        }
        val->label = strdup(vname);
        if (!val->label) return -1;
        for (int k = 0; k < v->n; k++) {
            char where[300];
            snprintf(where, sizeof where, "vary.%s.%s.%s", name, vname, v->keys[k]);
            if (make_override(&val->set[val->n], where, v->keys[k], v->items[k], path, err)) return -1;
            /* (where the loader names the key: the key's own place, not its value's) */
            val->set[val->n].line = v->key_line[k];
            val->set[val->n].col = v->key_col[k];
            val->n++;
            if (!sd_scenario_is_capture_key(v->keys[k])) a->capture = 0;
        }
    }
    return 0;
}

int sd_sweep_file_load(sd_sweep_file *d, const char *path, FILE *err)
{
    memset(d, 0, sizeof(*d));
    d->runs = 1;
    d->seed_base = 1;
    snprintf(d->path, sizeof d->path, "%s", path);
    char msg[1024];
    sd_ynode *root = sd_yaml_load(path, msg, sizeof msg);
    if (!root) {
        fprintf(err, "%s\n", msg);
        return -1;
    }
    int bad = 0;
    if (root->kind != SD_Y_MAP) {
        fprintf(err, "%s:%d:%d: a sweep file is a mapping (base, runs, vary, set)\n", path, root->line, root->col);
        bad = 1;
    }
    for (int i = 0; !bad && i < root->n; i++) {
        const char *k = root->keys[i];
        const sd_ynode *v = root->items[i];
        if (!strcmp(k, "base") && v->kind == SD_Y_SCALAR) {
            /* relative to the sweep file's directory */
            const char *slash = strrchr(path, '/');
            int n;
            if (v->value[0] != '/' && slash)
                n = snprintf(d->base, sizeof d->base, "%.*s/%s", (int)(slash - path), path, v->value);
            else
                n = snprintf(d->base, sizeof d->base, "%s", v->value);
            if (n < 0 || (size_t)n >= sizeof d->base || !v->value[0]) {
                fprintf(err, "%s:%d:%d: base: expected a scenario file's path (at most %zu characters)\n", path,
                        v->line, v->col, sizeof d->base - 1);
                bad = 1;
            }
        } else if ((!strcmp(k, "runs") || !strcmp(k, "seed_base") || !strcmp(k, "parallel")) &&
                   v->kind == SD_Y_SCALAR) {
            char *end;
            errno = 0;
            long x = strtol(v->value, &end, 10);
            const int runs = !strcmp(k, "runs"), seed = !strcmp(k, "seed_base");
            const long hi = runs ? SD_SWEEP_MAX_RUNS : seed ? 2147483647L - SD_SWEEP_MAX_RUNS : 4096;
            if (errno || end == v->value || *end || x < runs || x > hi) {
                fprintf(err, "%s:%d:%d: %s: expected an integer from %d to %ld\n", path, v->line, v->col, k, runs, hi);
                bad = 1;
            } else if (runs)
                d->runs = (int)x;
            else if (seed)
                d->seed_base = x;
            else
                d->parallel = (int)x;
        } else if (!strcmp(k, "vary") && v->kind == SD_Y_MAP) {
            for (int j = 0; j < v->n && !bad; j++)
                if (load_axis(d, v, j, err)) bad = 1;
        } else if (!strcmp(k, "set") && v->kind == SD_Y_MAP) {
            for (int j = 0; j < v->n && !bad; j++) {
                if (d->n_set == SD_SWEEP_MAX_SETS) {
                    fprintf(err, "%s:%d:%d: set: more than %d keys\n", path, v->key_line[j], v->key_col[j],
                            SD_SWEEP_MAX_SETS);
                    bad = 1;
                    break;
                }
                char where[300];
                snprintf(where, sizeof where, "set.%s", v->keys[j]);
                if (make_override(&d->set[d->n_set], where, v->keys[j], v->items[j], path, err))
                    bad = 1;
                else
                    d->n_set++;
            }
        } else {
            fprintf(err, "%s:%d:%d: unknown or malformed key '%s' (base, runs, seed_base, parallel, vary, set)\n", path,
                    root->key_line[i], root->key_col[i], k);
            bad = 1;
        }
    }
    /* a key varies along one axis at most (two would leave a case's value to their order) */
    for (int b = 1; b < d->n_axes && !bad; b++)
        for (int v = 0; v < d->axis[b].n_val && !bad; v++)
            for (int k = 0; k < d->axis[b].val[v].n && !bad; k++) {
                const sd_sweep_override *o = &d->axis[b].val[v].set[k];
                char key[SD_SWEEP_MAX_TEXT];
                override_key(o, key, sizeof key);
                for (int a = 0; a < b && !bad; a++)
                    if (axis_sets(&d->axis[a], key)) {
                        fprintf(err, "%s:%d:%d: vary.%s: %s is varied by vary.%s too (a key varies along one axis)\n",
                                path, o->line, o->col, d->axis[b].name, key, d->axis[a].name);
                        bad = 1;
                    }
            }
    /* the number of runs, in doubles: 8 keys of 32 values each are 32^8 cases, past any int */
    const double total = d->runs * sd_sweep_file_cases(d);
    if (!bad && total > SD_SWEEP_MAX_RUNS) {
        const sd_ynode *vn = sd_yaml_get(root, "vary");
        fprintf(err, "%s:%d:%d: vary: %.4g runs (cases x runs), more than %d: split the sweep\n", path,
                vn ? vn->line : 1, vn ? vn->col : 1, total, SD_SWEEP_MAX_RUNS);
        bad = 1;
    }
    if (!bad && !d->base[0]) {
        fprintf(err, "%s:1:1: missing 'base' (the scenario file to vary)\n", path);
        bad = 1;
    }
    sd_yaml_free(root);
    return bad ? -1 : 0;
}

void sd_sweep_file_free(sd_sweep_file *d)
{
    for (int a = 0; a < d->n_axes; a++)
        for (int v = 0; v < d->axis[a].n_val; v++) {
            free(d->axis[a].val[v].label);
            for (int k = 0; k < d->axis[a].val[v].n; k++)
                free(d->axis[a].val[v].set[k].text);
        }
    for (int k = 0; k < d->n_set; k++)
        free(d->set[k].text);
    memset(d, 0, sizeof *d);
}

double sd_sweep_file_cases(const sd_sweep_file *d)
{
    double n = 1.0;
    for (int a = 0; a < d->n_axes; a++)
        n *= d->axis[a].n_val;
    return n;
}

/* The loader's messages, with those about an override ("--set:N:C: ...") moved to the
 * override's place in the sweep file. */
static void relocate_messages(const char *text, const sd_sweep_override *const *from, int n, const char *path,
                              FILE *err)
{
    for (const char *line = text; line && *line;) {
        const char *nl = strchr(line, '\n');
        const int len = nl ? (int)(nl - line) : (int)strlen(line);
        int i = 0, col = 0, off = 0;
        if (sscanf(line, "--set:%d:%d: %n", &i, &col, &off) == 2 && off > 0 && off <= len && i >= 1 && i <= n &&
            from[i - 1])
            fprintf(err, "%s:%d:%d: %.*s\n", path, from[i - 1]->line, from[i - 1]->col, len - off, line + off);
        else
            fprintf(err, "%.*s\n", len, line);
        line = nl ? nl + 1 : NULL;
    }
}

int sd_sweep_file_scenario(const sd_sweep_file *d, const int *idx, long seed, sd_scenario *s, FILE *err)
{
    enum { MAX_OVERRIDES = SD_SWEEP_MAX_SETS + SD_SWEEP_MAX_AXES * SD_SWEEP_MAX_KEYS + 2 };
    const char *text[MAX_OVERRIDES];
    const sd_sweep_override *from[MAX_OVERRIDES];
    int n = 0;
    for (int k = 0; k < d->n_set; k++) {
        from[n] = &d->set[k];
        text[n++] = d->set[k].text;
    }
    for (int a = 0; a < d->n_axes; a++) {
        const sd_sweep_value *v = &d->axis[a].val[idx[a]];
        for (int k = 0; k < v->n; k++) {
            from[n] = &v->set[k];
            text[n++] = v->set[k].text;
        }
    }
    char seed_text[64];
    snprintf(seed_text, sizeof seed_text, "solver.seed=%ld", seed);
    from[n] = NULL;
    text[n++] = seed_text;
    from[n] = NULL;
    text[n++] = "solver.threads=1";
    char *msg = NULL;
    size_t msg_len = 0;
    FILE *m = open_memstream(&msg, &msg_len);
    const int bad = sd_scenario_load(s, d->base, text, n, m ? m : err);
    if (m) {
        fclose(m);
        relocate_messages(msg, from, n, d->path, err);
    }
    free(msg);
    return bad ? -1 : 0;
}
