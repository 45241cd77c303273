/* Materials in a scenario: the `materials:` and `contact_pairs:` lists, names to ids, the
 * springs each pair of materials gets (its own constants where given, contact.*'s for the
 * rest), what the world is given, and how `check` and summary.json report them. */
#include <ctype.h>
#include <math.h>
#include <stdarg.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "core/hash.h"
#include "core/nearest.h"
#include "core/vmath.h"
#include "scenario.h"
#include "yaml_tree.h"

static const char *const pair_keys[SD_PAIR_KEYS] = {"k_n", "k_s", "damping", "tan_phi", "cohesion"};
static const char *const use_names[] = {SD_MATERIAL_USES};
#define N_USES ((int)(sizeof use_names / sizeof use_names[0]))

const char *sd_scenario_pair_key(int k) { return k >= 0 && k < SD_PAIR_KEYS ? pair_keys[k] : NULL; }

#if defined(__GNUC__)
__attribute__((format(printf, 5, 6)))
#endif
static void say(sd_scenario_report_fn report, void *ctx, int line, int col, const char *fmt, ...)
{
    char msg[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    report(ctx, line, col, msg);
}

/* a letter or '_', then letters, digits, '_' or '-', shorter than SD_MATERIAL_NAME_MAX */
static int name_ok(const char *n)
{
    const size_t len = strlen(n);
    if (len == 0 || len >= SD_MATERIAL_NAME_MAX || !(isalpha((unsigned char)n[0]) || n[0] == '_')) return 0;
    for (size_t k = 1; k < len; k++)
        if (!(isalnum((unsigned char)n[k]) || n[k] == '_' || n[k] == '-')) return 0;
    return 1;
}

void sd_scenario_parse_materials(sd_scenario *s, const sd_ynode *list, sd_scenario_report_fn report, void *ctx)
{
    if (list->kind != SD_Y_SEQ) {
        say(report, ctx, list->line, list->col, "materials: expected a list of names ([rock, wood] or [{name: rock}])");
        return;
    }
    for (int i = 0; i < list->n; i++) {
        const sd_ynode *it = list->items[i], *nm = it;
        if (it->kind == SD_Y_MAP) {
            for (int k = 0; k < it->n; k++)
                if (strcmp(it->keys[k], "name") != 0)
                    say(report, ctx, it->key_line[k], it->key_col[k],
                        "materials: unknown key '%s' (a material has a name; its springs go in contact_pairs)",
                        it->keys[k]);
            nm = sd_yaml_get(it, "name");
            if (!nm) {
                say(report, ctx, it->line, it->col, "materials: each entry needs a name");
                continue;
            }
        }
        if (nm->kind != SD_Y_SCALAR || !name_ok(nm->value)) {
            say(report, ctx, nm->line, nm->col,
                "materials: '%s' is not a name (a letter or _, then letters, digits, _ or -; at most %d)",
                nm->kind == SD_Y_SCALAR ? nm->value : "(a list or mapping)", SD_MATERIAL_NAME_MAX - 1);
            continue;
        }
        if (!strcmp(nm->value, "default")) {
            say(report, ctx, nm->line, nm->col,
                "materials: 'default' is the material of everything given none; name it in contact_pairs without "
                "declaring it");
            continue;
        }
        int dup = 0;
        for (int m = 1; m < s->n_materials; m++)
            dup |= !strcmp(s->material_name[m], nm->value);
        if (dup) {
            say(report, ctx, nm->line, nm->col, "materials: '%s' is declared twice", nm->value);
            continue;
        }
        if (s->n_materials == SD_MATERIALS_MAX) {
            say(report, ctx, nm->line, nm->col, "materials: at most %d materials besides default", SD_MATERIALS_MAX - 1);
            return;
        }
        snprintf(s->material_name[s->n_materials++], SD_MATERIAL_NAME_MAX, "%s", nm->value);
    }
}

int sd_scenario_material_id(const sd_scenario *s, const char *name, char *hint, size_t hint_len)
{
    const char *cand[SD_MATERIALS_MAX];
    for (int m = 0; m < s->n_materials; m++) {
        if (!strcmp(s->material_name[m], name)) return m;
        cand[m] = s->material_name[m];
    }
    if (hint && hint_len > 0) {
        const char *near = sd_nearest_word(name, cand, (size_t)s->n_materials);
        if (near) {
            snprintf(hint, hint_len, " (did you mean '%s'?)", near);
        } else {
            size_t n = (size_t)snprintf(hint, hint_len, " (the materials: ");
            for (int m = 0; m < s->n_materials && n < hint_len; m++)
                n += (size_t)snprintf(hint + n, hint_len - n, "%s%s", m ? ", " : "", s->material_name[m]);
            if (n < hint_len) snprintf(hint + n, hint_len - n, "; declare it under materials:)");
        }
    }
    return -1;
}

void sd_scenario_parse_pairs(sd_scenario *s, const sd_ynode *list, sd_pair_value_fn value, sd_scenario_report_fn report,
                             void *ctx)
{
    if (list->kind != SD_Y_SEQ) {
        say(report, ctx, list->line, list->col,
            "contact_pairs: expected a list of {pair: [material, material], k_n: ..., tan_phi: ...}");
        return;
    }
    for (int i = 0; i < list->n; i++) {
        const sd_ynode *it = list->items[i];
        if (it->kind != SD_Y_MAP) {
            say(report, ctx, it->line, it->col, "contact_pairs: each entry is a mapping {pair: [a, b], ...}");
            continue;
        }
        sd_pair_def d;
        memset(&d, 0, sizeof d);
        d.line = it->line;
        d.col = it->col;
        int ok = 1;
        const sd_ynode *pr = NULL;
        for (int k = 0; k < it->n; k++) {
            const char *key = it->keys[k];
            const sd_ynode *v = it->items[k];
            if (!strcmp(key, "pair")) {
                pr = v;
                continue;
            }
            int q = 0;
            while (q < SD_PAIR_KEYS && strcmp(key, pair_keys[q]))
                q++;
            if (q == SD_PAIR_KEYS) {
                const char *const known[SD_PAIR_KEYS + 1] = {"pair", "k_n", "k_s", "damping", "tan_phi", "cohesion"};
                const char *near = sd_nearest_word(key, known, SD_PAIR_KEYS + 1);
                char hint[64] = " (pair, k_n, k_s, damping, tan_phi, cohesion)";
                if (near) snprintf(hint, sizeof hint, " (did you mean '%s'?)", near);
                say(report, ctx, it->key_line[k], it->key_col[k], "contact_pairs: unknown key '%s'%s", key, hint);
                ok = 0;
                continue;
            }
            char why[160];
            if (value(q, v->kind == SD_Y_SCALAR ? v->value : NULL, &d.v[q], why, sizeof why)) {
                say(report, ctx, v->line, v->col, "contact_pairs.%s: %s", key, why);
                ok = 0;
                continue;
            }
            d.given |= 1u << q;
        }
        if (!pr) {
            say(report, ctx, it->line, it->col, "contact_pairs: each entry needs pair: [material, material]");
            continue;
        }
        if (pr->kind != SD_Y_SEQ || pr->n != 2 || pr->items[0]->kind != SD_Y_SCALAR || pr->items[1]->kind != SD_Y_SCALAR) {
            say(report, ctx, pr->line, pr->col, "contact_pairs.pair: expected two material names [a, b]");
            continue;
        }
        int id[2];
        for (int q = 0; q < 2; q++) {
            char hint[SD_MATERIALS_MAX * SD_MATERIAL_NAME_MAX + 64];
            id[q] = sd_scenario_material_id(s, pr->items[q]->value, hint, sizeof hint);
            if (id[q] < 0) {
                say(report, ctx, pr->items[q]->line, pr->items[q]->col, "contact_pairs.pair: unknown material '%s'%s",
                    pr->items[q]->value, hint);
                ok = 0;
            }
        }
        if (!ok) continue;
        d.a = id[0] < id[1] ? id[0] : id[1];
        d.b = id[0] < id[1] ? id[1] : id[0];
        int first = 0;
        for (int p = 0; p < s->n_pairs && !first; p++)
            if (s->pairs[p].a == d.a && s->pairs[p].b == d.b) first = s->pairs[p].line;
        if (first) {
            say(report, ctx, pr->line, pr->col, "contact_pairs: the pair [%s, %s] is given twice (first at line %d)",
                pr->items[0]->value, pr->items[1]->value, first);
            continue;
        }
        s->pairs[s->n_pairs++] = d; /* (at most SD_MAX_PAIRS: every pair once) */
    }
}

sd_contact_def sd_scenario_pair_contact(const sd_scenario *s, int a, int b, int *own)
{
    sd_contact_def c = s->world.contact;
    double *field[SD_PAIR_KEYS] = {&c.k_n, &c.k_s, &c.damping, &c.tan_phi, &c.cohesion};
    const int lo = a < b ? a : b, hi = a < b ? b : a;
    if (own) *own = 0;
    for (int p = 0; p < s->n_pairs; p++) {
        const sd_pair_def *d = &s->pairs[p];
        if (d->a != lo || d->b != hi) continue;
        for (int k = 0; k < SD_PAIR_KEYS; k++)
            if (d->given & (1u << k)) *field[k] = d->v[k];
        if (own) *own = 1;
    }
    return c;
}

sd_status sd_scenario_apply_materials(const sd_scenario *s, sd_world *w)
{
    for (int p = 0; p < s->n_pairs; p++) {
        const sd_contact_def c = sd_scenario_pair_contact(s, s->pairs[p].a, s->pairs[p].b, NULL);
        const sd_status st = sd_world_set_pair_contact(w, s->pairs[p].a, s->pairs[p].b, &c);
        if (st) return st;
    }
    return SD_OK;
}

/* The logs a flume gets: some unless logs.count is 0, or -1 with K_w = 0 (build.c counts them) */
static int has_logs(const sd_scenario *s) { return s->log_count > 0 || (s->log_count < 0 && s->log_kw > 0); }

static int class_mat(const sd_scenario *s, int k) { return s->n_sphere_mats == 0 ? 0 : s->sphere_mat[s->n_sphere_mats == 1 ? 0 : k]; }

static double sphere_mass(double d, double rho) { return rho * M_PI / 6.0 * d * d * d; }

/* what uses each material (bits in use_names' order), and each material's lightest moving mass */
static void scan(const sd_scenario *s, unsigned uses[SD_MATERIALS_MAX], double mmin[SD_MATERIALS_MAX])
{
    for (int m = 0; m < SD_MATERIALS_MAX; m++) {
        uses[m] = 0;
        mmin[m] = INFINITY;
    }
    enum { U_SPHERES, U_LOGS, U_DAM, U_BED, U_WALLS, U_ROUGH, U_GATE, U_PILE, U_BOX, U_ELEMENTS, U_MESHES };
    for (int i = 0; i < s->n_elems; i++) {
        const sd_elem_def *d = &s->elems[i];
        uses[d->material] |= 1u << U_ELEMENTS;
        if (d->fixed || d->type == 2) continue;
        const double m = d->type == 0 ? sphere_mass(2.0 * d->radius, d->density)
                                      : d->density * M_PI * d->radius * d->radius * d->length;
        mmin[d->material] = fmin(mmin[d->material], m);
    }
    for (int k = 0; k < s->n_meshes; k++)
        uses[s->meshes[k].material] |= 1u << U_MESHES;
    if (s->box_on) uses[s->box_mat] |= 1u << U_BOX;
    for (int k = 0; k < s->pile_n_classes; k++)
        if (s->pile_count[k] > 0) {
            uses[s->pile_mat] |= 1u << U_PILE;
            mmin[s->pile_mat] = fmin(mmin[s->pile_mat], sphere_mass(s->pile_diam[k], s->pile_density));
        }
    if (!s->flume_on) return;
    if (s->flume_bed) uses[s->bed_mat] |= 1u << U_BED;
    uses[s->wall_mat] |= 1u << U_WALLS;
    uses[s->gate_mat] |= 1u << U_GATE;
    if (s->roughness_on) uses[s->rough_mat] |= 1u << U_ROUGH;
    if (s->dam_on) uses[s->pipe_mat] |= 1u << U_DAM;
    for (int k = 0; k < s->n_classes; k++)
        if (s->class_count[k] > 0) {
            const int m = class_mat(s, k);
            uses[m] |= 1u << U_SPHERES;
            mmin[m] = fmin(mmin[m], sphere_mass(s->class_diam[k], s->sphere_density));
        }
    if (has_logs(s)) { /* the smallest log the distributions can draw */
        const double d = s->log_diam_dist.type ? s->log_diam_dist.min : s->log_diam;
        const double l = s->log_length_dist.type ? s->log_length_dist.min : s->log_length;
        uses[s->log_mat] |= 1u << U_LOGS;
        mmin[s->log_mat] = fmin(mmin[s->log_mat], s->log_density * M_PI * 0.25 * d * d * l);
    }
}

void sd_scenario_material_uses(const sd_scenario *s, unsigned uses[SD_MATERIALS_MAX])
{
    double mmin[SD_MATERIALS_MAX];
    scan(s, uses, mmin);
}

double sd_scenario_stable_dt(const sd_scenario *s, int *pa, int *pb, double *pm)
{
    unsigned uses[SD_MATERIALS_MAX];
    double mmin[SD_MATERIALS_MAX];
    scan(s, uses, mmin);
    /* sd_world_stable_dt's rule: each moving material against everything present */
    double dt = INFINITY;
    int best_a = 0, best_b = 0;
    for (int a = 0; a < SD_MATERIALS_MAX; a++)
        for (int b = 0; b < SD_MATERIALS_MAX && isfinite(mmin[a]); b++) {
            if (!uses[b]) continue;
            const sd_contact_def c = sd_scenario_pair_contact(s, a, b, NULL);
            const double d = sd_stable_dt_max(c.k_n, c.k_s, mmin[a]);
            if (d < dt) {
                dt = d;
                best_a = a;
                best_b = b;
            }
        }
    if (pa) *pa = best_a;
    if (pb) *pb = best_b;
    if (pm) *pm = mmin[best_a];
    return dt;
}

/* The pairs a report lists: those of two materials that can meet (both used, one of them by
 * something that moves), and those given in contact_pairs. */
static int listed(const sd_scenario *s, const unsigned *uses, const double *mmin, int a, int b, int *meet)
{
    int own;
    (void)sd_scenario_pair_contact(s, a, b, &own);
    *meet = uses[a] && uses[b] && (isfinite(mmin[a]) || isfinite(mmin[b]));
    return *meet || own;
}

static void uses_text(unsigned u, char *buf, size_t n)
{
    size_t len = 0;
    buf[0] = 0;
    for (int k = 0; k < N_USES && len < n; k++)
        if (u & (1u << k)) len += (size_t)snprintf(buf + len, n - len, "%s%s", len ? ", " : "", use_names[k]);
    if (!u) snprintf(buf, n, "unused");
}

cJSON *sd_scenario_materials_json(const sd_scenario *s)
{
    unsigned uses[SD_MATERIALS_MAX];
    double mmin[SD_MATERIALS_MAX];
    scan(s, uses, mmin);
    cJSON *o = cJSON_CreateObject(), *mats = o ? cJSON_AddArrayToObject(o, "materials") : NULL;
    cJSON *pairs = mats ? cJSON_AddArrayToObject(o, "contact_pairs") : NULL;
    int bad = !pairs;
    for (int m = 0; m < s->n_materials && !bad; m++) {
        cJSON *e = cJSON_CreateObject(), *u = NULL;
        bad = !e || !cJSON_AddStringToObject(e, "name", s->material_name[m]) || !cJSON_AddNumberToObject(e, "id", m) ||
              !(u = cJSON_AddArrayToObject(e, "used_by"));
        for (int k = 0; k < N_USES && !bad; k++)
            if (uses[m] & (1u << k)) bad = !cJSON_AddItemToArray(u, cJSON_CreateString(use_names[k]));
        if (!e || !cJSON_AddItemToArray(mats, e)) {
            cJSON_Delete(e);
            bad = 1;
        }
    }
    for (int a = 0; a < s->n_materials && !bad; a++)
        for (int b = a; b < s->n_materials && !bad; b++) {
            int meet, own;
            if (!listed(s, uses, mmin, a, b, &meet)) continue;
            const sd_contact_def c = sd_scenario_pair_contact(s, a, b, &own);
            const double v[SD_PAIR_KEYS] = {c.k_n, c.k_s, c.damping, c.tan_phi, c.cohesion};
            const char *names[2] = {s->material_name[a], s->material_name[b]};
            cJSON *e = cJSON_CreateObject();
            bad = !e || !cJSON_AddItemToObject(e, "pair", cJSON_CreateStringArray(names, 2));
            for (int k = 0; k < SD_PAIR_KEYS && !bad; k++)
                bad = !cJSON_AddNumberToObject(e, pair_keys[k], v[k]);
            bad = bad || !cJSON_AddStringToObject(e, "from", own ? "contact_pairs" : "contact") ||
                  !cJSON_AddBoolToObject(e, "can_meet", meet);
            if (!e || !cJSON_AddItemToArray(pairs, e)) {
                cJSON_Delete(e);
                bad = 1;
            }
        }
    if (bad) {
        cJSON_Delete(o);
        return NULL;
    }
    return o;
}

void sd_scenario_materials_report(FILE *f, const sd_scenario *s)
{
    unsigned uses[SD_MATERIALS_MAX];
    double mmin[SD_MATERIALS_MAX];
    scan(s, uses, mmin);
    char u[160];
    if (s->n_materials == 1 && s->n_pairs == 0) {
        const sd_contact_def c = s->world.contact;
        fprintf(f, "materials: one: every contact K_n = %g N/m, K_s = %g N/m, h = %g, tan phi = %g, c = %g N\n", c.k_n,
                c.k_s, c.damping, c.tan_phi, c.cohesion);
        return;
    }
    fprintf(f, "materials:");
    for (int m = 0; m < s->n_materials; m++) {
        uses_text(uses[m], u, sizeof u);
        fprintf(f, "%s %s (%s)", m ? "," : "", s->material_name[m], u);
    }
    fprintf(f, "\n  springs of each pair (* from contact_pairs, the rest from contact.*; - cannot meet):\n");
    fprintf(f, "     %-31s %10s %10s %7s %7s %8s\n", "pair", "K_n N/m", "K_s N/m", "h", "tan phi", "c N");
    for (int a = 0; a < s->n_materials; a++)
        for (int b = a; b < s->n_materials; b++) {
            int meet, own;
            if (!listed(s, uses, mmin, a, b, &meet)) continue;
            const sd_contact_def c = sd_scenario_pair_contact(s, a, b, &own);
            char pair[2 * SD_MATERIAL_NAME_MAX + 4];
            snprintf(pair, sizeof pair, "%s%s-%s", own ? "*" : " ", s->material_name[a], s->material_name[b]);
            fprintf(f, "   %c%-32s %10g %10g %7g %7g %8g\n", meet ? ' ' : '-', pair, c.k_n, c.k_s, c.damping, c.tan_phi,
                    c.cohesion);
        }
}

uint64_t sd_scenario_materials_hash(const sd_scenario *s, uint64_t h)
{
    h = sd_hash_bytes(h, &s->n_materials, sizeof s->n_materials);
    for (int m = 0; m < s->n_materials; m++)
        h = sd_hash_bytes(h, s->material_name[m], strlen(s->material_name[m]) + 1);
    h = sd_hash_bytes(h, &s->n_pairs, sizeof s->n_pairs);
    for (int p = 0; p < s->n_pairs; p++) { /* field by field (the struct has padding) */
        const sd_pair_def *d = &s->pairs[p];
        h = sd_hash_bytes(h, &d->a, sizeof d->a);
        h = sd_hash_bytes(h, &d->b, sizeof d->b);
        h = sd_hash_bytes(h, &d->given, sizeof d->given);
        for (int k = 0; k < SD_PAIR_KEYS; k++)
            if (d->given & (1u << k)) h = sd_hash_bytes(h, &d->v[k], sizeof d->v[k]);
    }
    return h;
}
