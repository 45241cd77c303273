/* A shared flow checkpoint's identity (sweep_identity.h), as JSON through cJSON:
 *   {"about": "...", "engine": "sabodem 0.9.0 (git ...), checkpoint format 1, driver state SDRUNv3",
 *    "scenario_hash": "<16 hex digits: sd_scenario_branch_hash>",
 *    "scenario": {"solver.seed": 1, "spheres.counts": [20, 40, 120], ...}}
 * The hash decides; the values are there to say which keys changed. A separate file and not a
 * section of the checkpoint, so that it is read before (and instead of) a checkpoint that
 * another engine may not even be able to read. */
#include "sweep_identity.h"

#include <cjson/cJSON.h>
#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "run.h"
#include "sabodem_run.h"

#define MAX_IDENTITY_BYTES (1 << 20)

void sd_sweep_identity_engine(char *buf, size_t n)
{
    snprintf(buf, n, "sabodem %s (%s), checkpoint format %u, driver state %s", sd_version(), sd_build_id(),
             (unsigned)sd_checkpoint_version(), sd_run_state_version());
}

/* the values of the keys the branch hash counts */
static cJSON *branch_keys(const sd_scenario *s)
{
    cJSON *o = sd_scenario_params_json(s);
    for (cJSON *it = o ? o->child : NULL, *next; it; it = next) {
        next = it->next;
        if (!sd_scenario_in_branch_hash(it->string)) cJSON_Delete(cJSON_DetachItemViaPointer(o, it));
    }
    return o;
}

static void hash_text(const sd_scenario *s, char buf[17])
{
    snprintf(buf, 17, "%016llx", (unsigned long long)sd_scenario_branch_hash(s));
}

int sd_sweep_identity_write(const char *path, const sd_scenario *s)
{
    char engine[512], hash[17], tmp[1400];
    sd_sweep_identity_engine(engine, sizeof engine);
    hash_text(s, hash);
    cJSON *o = cJSON_CreateObject(), *keys = branch_keys(s);
    char *text = NULL;
    if (o && keys &&
        cJSON_AddStringToObject(o, "about",
                                "the identity of flow_end.ckpt beside it: a sweep branches from that checkpoint only "
                                "when the engine and the scenario up to the flow end match (docs/sweep.md)") &&
        cJSON_AddStringToObject(o, "engine", engine) && cJSON_AddStringToObject(o, "scenario_hash", hash)) {
        cJSON_AddItemToObject(o, "scenario", keys);
        keys = NULL;
        text = cJSON_Print(o);
    }
    cJSON_Delete(keys);
    cJSON_Delete(o);
    if (!text) {
        errno = ENOMEM;
        return -1;
    }
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    FILE *f = fopen(tmp, "w");
    int bad = !f;
    if (f) {
        bad = fputs(text, f) < 0 || fputc('\n', f) == EOF || fflush(f) || fsync(fileno(f));
        bad |= fclose(f) != 0;
    }
    free(text);
    if (bad || rename(tmp, path)) {
        const int e = errno;
        remove(tmp);
        errno = e;
        return -1;
    }
    return 0;
}

/* the file's text (NUL-terminated, malloc'ed), or NULL */
static char *read_text(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    char *buf = malloc(MAX_IDENTITY_BYTES + 1);
    size_t n = buf ? fread(buf, 1, MAX_IDENTITY_BYTES + 1, f) : 0;
    fclose(f);
    if (!buf || n > MAX_IDENTITY_BYTES) {
        free(buf);
        return NULL;
    }
    buf[n] = '\0';
    return buf;
}

/* "k: a -> b" for each key whose value differs, into msg from len on */
static void list_changes(const cJSON *was, const cJSON *now, char *msg, size_t n, size_t len)
{
    int listed = 0, more = 0;
    for (const cJSON *it = now ? now->child : NULL; it; it = it->next) {
        const cJSON *old = was ? cJSON_GetObjectItemCaseSensitive(was, it->string) : NULL;
        if (old && cJSON_Compare(old, it, 1)) continue;
        if (len >= n) break;
        if (listed == 4) {
            more++;
            continue;
        }
        char *a = old ? cJSON_PrintUnformatted(old) : NULL, *b = cJSON_PrintUnformatted(it);
        const int w = snprintf(msg + len, len < n ? n - len : 0, "%s%s %.60s -> %.60s", listed ? ", " : "", it->string,
                               a ? a : "(absent)", b ? b : "?");
        free(a);
        free(b);
        if (w > 0) len += (size_t)w;
        listed++;
    }
    if (more && len < n)
        snprintf(msg + len, n - len, " and %d more", more);
    else if (!listed && len < n)
        snprintf(msg + len, n - len, "the explicit elements or other settings differ");
}

int sd_sweep_identity_check(const char *path, const sd_scenario *s, char *msg, size_t n)
{
    char *text = read_text(path);
    if (!text) {
        snprintf(msg, n, "%s: %s", path, errno == ENOENT ? "missing" : "cannot be read");
        return SD_IDENTITY_NONE;
    }
    cJSON *o = cJSON_Parse(text);
    free(text);
    const cJSON *engine = cJSON_GetObjectItemCaseSensitive(o, "engine");
    const cJSON *hash = cJSON_GetObjectItemCaseSensitive(o, "scenario_hash");
    if (!cJSON_IsString(engine) || !cJSON_IsString(hash)) {
        snprintf(msg, n, "%s: not a flow checkpoint's identity (no engine or scenario_hash)", path);
        cJSON_Delete(o);
        return SD_IDENTITY_NONE;
    }
    char mine[512], my_hash[17];
    sd_sweep_identity_engine(mine, sizeof mine);
    hash_text(s, my_hash);
    int code = SD_IDENTITY_SAME;
    if (strcmp(engine->valuestring, mine)) {
        snprintf(msg, n, "made by another engine: %.400s; this is %s", engine->valuestring, mine);
        code = SD_IDENTITY_ENGINE;
    } else if (strcmp(hash->valuestring, my_hash)) {
        cJSON *now = branch_keys(s);
        const int len = snprintf(msg, n, "made for other values of keys that act before the flow end: ");
        list_changes(cJSON_GetObjectItemCaseSensitive(o, "scenario"), now, msg, n, len > 0 ? (size_t)len : 0);
        cJSON_Delete(now);
        code = SD_IDENTITY_SCENARIO;
    }
    cJSON_Delete(o);
    return code;
}
