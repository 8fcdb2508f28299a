# enact-hub 页面，简体中文。每个键都必须与 locales/en/pages.ftl 一一对应。

## 每个页面的框架
nav-label = 站点
nav-datasets = 数据集
nav-studies = 研究
nav-annotate = 标注
footer = enact-hub · ENACT 具身世界建模基准的评测服务

## 错误页面
error-detail = 详细信息（系统原文，英文）：
error-back = 返回数据集
error-reason-400 = 请求有误
error-explain-400 = 无法理解该请求：其中有内容缺失或格式不正确。
error-reason-401 = 未登录
error-explain-401 = 您尚未登录，或会话已过期。
error-reason-403 = 禁止访问
error-explain-403 = 您无权执行此操作。
error-reason-404 = 未找到
error-explain-404 = 此处没有内容：该页面、数据集或条目不存在。
error-reason-409 = 冲突
error-explain-409 = 该操作与已保存的内容冲突。
error-reason-413 = 内容过大
error-explain-413 = 发送的内容超出了本服务接受的大小。
error-reason-415 = 不支持的格式
error-explain-415 = 发送的内容不是本服务能读取的格式。
error-reason-422 = 内容无效
error-explain-422 = 发送的内容已读取，但其中部分内容无效。
error-reason-429 = 请求过多
error-explain-429 = 尝试次数过多：请稍候再试。
error-reason-500 = 服务器内部错误
error-explain-500 = 服务端出现问题，已记录在日志中。
error-reason-503 = 服务暂不可用
error-explain-503 = 本服务暂时无法完成此操作：请稍后再试。

## 拒绝原因：请求被拒绝的原因，每个类型化原因一条消息（src/app/refusal.rs）。
refusal-no-dataset = 没有名为“{ $dataset }”的数据集
refusal-no-item = 数据集“{ $dataset }”中没有条目“{ $item }”
refusal-no-annotator = 没有名为“{ $annotator }”的标注员
refusal-no-episode = 没有名为“{ $episode }”的片段
refusal-no-submission = 没有编号为 { $submission } 的提交
refusal-no-run = 没有模型运行 { $run }
refusal-no-frame = 没有哈希为“{ $frame }”的帧
refusal-no-answer-yet = 您尚未作答条目“{ $item }”
refusal-not-logged-in = 您尚未登录，或会话已过期：请重新登录
refusal-login-link-used = 此登录链接无效或已被使用：每个链接只能登录一次；请向管理员索取新链接，或用密码登录
refusal-admin-only = 管理页面仅供管理员使用；“{ $annotator }”是标注员
refusal-stale-form = 此页面的表单已过期：请刷新页面后重试
refusal-not-assigned = 数据集“{ $dataset }”的条目“{ $item }”未分配给您
refusal-item-finished = 条目“{ $item }”已完成，其答案不能再更改
refusal-queue-paused = 管理员已暂停您的队列（自 { $since } 起）：在队列恢复之前，您不能打开、保存、作答或跳过条目；您的草稿会保留
refusal-draft-slot-count = 条目“{ $item }”的草稿在 { $field } 中有 { $given } 个槽位；该条目有 { $expected } 个
refusal-draft-label-out-of-range = 条目“{ $item }”的草稿在 { $field } 的第 { $slot } 个槽位放了卡片 { $label }；该条目的卡片为 1 到 { $labels }
refusal-draft-placed-twice = 条目“{ $item }”的草稿把卡片 { $label } 放了两次（{ $field }，第 { $slot } 个槽位再次出现）
refusal-draft-history-too-long = 条目“{ $item }”的草稿有 { $entries } 步撤销记录；最多保留 { $most } 步
refusal-slots-empty = 条目“{ $item }”：提交前请填满所有槽位（空槽位：{ $slots }）
refusal-reason-missing = { $action ->
        [flag] 要报告条目“{ $item }”的问题，请在原因栏中说明原因
       *[skip] 要跳过条目“{ $item }”，请在原因栏中说明原因
    }
refusal-reason-too-long = 原因超过 { $limit } 个字符
refusal-passwords-differ = 两次输入的密码不一致
refusal-password-too-short = 密码只有 { $chars } 个字符；至少需要 { $least } 个
refusal-episode-has-no-graphs = 片段“{ $episode }”还没有场景图：须由整理者设置后才能导出
refusal-run-price = { $field } 须为 0 或以上的价格（美元/百万词元），而不是 { $price }
refusal-study-exists = 名为“{ $study }”的研究已存在
refusal-study-baseline-missing = 基线：没有名为“{ $dataset }”的数据集
refusal-study-variant-missing = 变体 { $variant }：没有名为“{ $dataset }”的数据集
refusal-study-variant-unaligned = 变体 { $variant }：数据集“{ $dataset }”的 { $items } 个条目中没有一个与基线“{ $baseline }”的 { $baseline_items } 个条目对齐（按编号，或按任务、类型和关键帧）；变体应以其他图像提出基线的问题（由基线的条目生成）
refusal-import-folder-unset = 本服务器只有在运维者指定导入文件夹（ENACT_HUB_IMPORT_DIR）时才从自己的磁盘导入发布包；否则请在服务器上直接导入
refusal-import-path-not-relative = 路径：“{ $path }”须为相对于服务器导入文件夹的发布包路径
refusal-import-path-missing = 路径：服务器的导入文件夹中没有“{ $path }”
refusal-import-path-leaves-folder = 路径：“{ $path }”超出了服务器的导入文件夹
refusal-import-path-not-a-release = 路径：“{ $path }”既不是发布包文件夹（含 QA/enact_ordering.jsonl），也不是 .jsonl 文件
refusal-import-release-leaves-folder = 路径：“{ $path }”的发布包（其图像文件夹）超出了服务器的导入文件夹
refusal-challenge-not-split = 数据集“{ $dataset }”尚未划分为公开部分和私有部分：须先由管理员在“挑战”页面划分
refusal-challenge-revealed = 数据集“{ $dataset }”的私有部分已于 { $at } { $how ->
        [deadline] 在截止时间
       *[hand] 由管理员手动
    }揭晓：最终排名、其设置和所选提交均已固定
refusal-challenge-answers-public = 数据集“{ $dataset }”：其答案是公开的，任何提交者都能为其任一部分评分；只有答案隐藏的数据集才能划分（请先隐藏答案）
refusal-challenge-too-few-items = 数据集“{ $dataset }”有 { $items } 个条目：划分至少需要两个
refusal-challenge-already-split = 数据集“{ $dataset }”已于 { $at } 由 { $by } 划分（种子 { $seed }，公开比例 { $public_share }）；划分不可更改
refusal-selection-not-published = 提交 { $submission } 的状态为 { $visibility }：只有已发布的提交才能被选入最终排名
refusal-selection-limit-reached = 数据集“{ $dataset }”每个账户最多可选 { $limit } 个提交：账户“{ $account }”已选 { $selected }；请先撤下一个
refusal-private-part-hidden = 数据集“{ $dataset }”的私有部分尚未揭晓{ $scheduled ->
        [yes] （将于 { $reveal_at } 揭晓）
       *[no] {""}
    }；在此之前其数据仅供管理员查看
refusal-bad-value-whole-number = { $field }：“{ $value }”不是 { $least } 到 { $most } 之间的整数
refusal-bad-value-whole-number-from = { $field }：“{ $value }”不是大于或等于 { $least } 的整数
refusal-bad-value-number = { $field }：“{ $value }”不是数字
refusal-bad-value-number-between = { $field }：“{ $value }”不是 { $least } 到 { $most } 之间的数字
refusal-bad-value-fraction = { $field }：“{ $value }”不是大于 0 且小于 1 的数字
refusal-bad-value-one-of = { $field }：“{ $value }”不是以下之一：{ $choices }
refusal-bad-value-submission-id = { $field }：“{ $value }”不是提交编号
refusal-bad-value-reported-id = { $field }：“{ $value }”不是已报告结果的编号
refusal-no-study = 没有名为“{ $study }”的研究
refusal-no-token = 没有编号或前缀为“{ $token }”的有效令牌
refusal-no-job = 任务 { $job } 不存在
refusal-no-reported = 数据集“{ $dataset }”没有编号为 { $reported } 的已报告结果
refusal-no-curator-graphs = 整理者“{ $curator }”没有保存片段“{ $episode }”的场景图
refusal-answers-hidden = 数据集“{ $dataset }”的答案是隐藏的，因此不显示会透露答案的内容
refusal-invite-link-used = 此邀请链接未知或已被使用：请向管理员索取新链接
refusal-no-model-submission = 数据集“{ $dataset }”上没有模型“{ $model }”的提交
refusal-no-published-submission = { $field }：数据集“{ $dataset }”没有已发布的提交 { $submission }
refusal-no-published-model = { $field }：数据集“{ $dataset }”没有模型“{ $model }”的已发布行{ $listed ->
        [yes] （其模型：{ $models }）
       *[no] {""}
    }
refusal-no-paper-file = 数据集“{ $dataset }”的论文文件夹中没有文件“{ $file }”（现有：{ $files }）
refusal-no-api-route = 没有 API 路由 { $path }：所有路由列于 /api/docs
refusal-fields-required = 此请求需要：{ $fields }
refusal-exactly-one-of = 请只给出以下其中之一：{ $fields }
refusal-both-or-neither = { $fields } 须同时给出，或都不给
refusal-not-with = { $field } 不能与 { $other } 同时给出
refusal-token-missing = 此请求需要 API 令牌
refusal-authorization-malformed = Authorization 请求头的格式须为“Bearer TOKEN”
refusal-token-unknown = 此 API 令牌未知或已被撤销
refusal-scope-missing = 此令牌缺少“{ $scope }”权限范围
refusal-not-model-owner = 数据集“{ $dataset }”上的模型“{ $model }”由另一个账户提交；只有该账户或管理员可以设置其元数据
refusal-empty-list = { $field }：请至少给出一项
refusal-listed-twice = { $field }：条目“{ $item }”出现了两次
refusal-leaves-no-items = { $field }：列表包含了数据集“{ $dataset }”的所有条目；请为人类行留下一些
refusal-too-few-for-gold = 数据集“{ $dataset }”只有 { $items } 个条目；金标准条目至少需要两个，以便为人类行留下一些
refusal-gold-and-attention = { $field }：数据集“{ $dataset }”的 { $items } { $field ->
        [checks] 是金标准条目，不能同时作为注意力检查
       *[items] 是注意力检查，不能同时作为金标准条目
    }
refusal-all-chosen-paused = 为划分选中的每位标注者的队列都已暂停：请恢复其中一位，或另选他人
refusal-recipient-paused = 标注者“{ $annotator }”的队列已暂停；请恢复该队列或另选他人
refusal-handover-to-self = “{ $annotator }”不能把条目移交给自己
refusal-no-recipient = 没有其他队列正在运行的活跃标注者可以接收“{ $annotator }”的条目：请新建一位、恢复一位，或指定接收者
refusal-dataset-exists = 名为“{ $dataset }”的数据集已存在
refusal-daily-quota-used = 此令牌今天（UTC）的 { $limit } 次提交已用完；请在 { $retry_after } 秒后重试
refusal-total-quota-used = 此令牌的总配额已用完：已提交 { $used } 次，共 { $limit } 次；等待无济于事，请向管理员申请新令牌或更大的总配额
refusal-idempotency-key-reused = 此 Idempotency-Key 已用于提交 { $submission }，但请求体不同

## 登录
login-title = 登录
login-heading = 登录以进行标注
login-name = 用户名
login-password = 密码
login-submit = 登录
login-no-account = 还没有账号？请由管理员创建账号，并向您发送一次性邀请链接。
login-error-expired = 登录表单已过期或缺少 CSRF 令牌：请重试
login-error-missing = 请填写用户名和密码
login-error-wrong = 用户名不存在或密码错误
login-error-limited = 登录失败次数过多：请在 { $minutes } 分钟后重试

## 标注队列
queue-title = 我的队列
queue-logged-in-as = 当前登录：
queue-admin = 管理
queue-log-out = 退出登录
queue-finished = 已完成 { $done } / { $total } 个条目。
queue-resume = 从上次中断处继续
queue-continue = 继续
queue-all-done = 分配给您的条目已全部完成，谢谢！
queue-empty = 目前还没有分配给您的条目。
queue-paused = 管理员已暂停您的队列。您仍可查看自己的条目，但在队列恢复之前不能打开、作答或跳过条目；您的草稿会保留。
queue-progress-caption = 已完成 / 已分配，按方向和步长统计（L = 图像数量）

## 表头与基准术语
col-direction = 方向
col-item = 条目
col-dataset = 数据集
col-status = 状态
direction-forward = 正向
direction-inverse = 逆向
status-todo = 待完成
status-started = 进行中
status-answered = 已作答
status-skipped = 已跳过
status-flagged = 已标记问题

## 标注页面（正向与逆向）
annotate-title-forward = 正向条目
annotate-title-inverse = 逆向条目
annotate-task-forward = 正向世界建模：按动作产生的顺序排列未来图像
annotate-task-inverse = 逆向世界建模：为每个状态转变选出导致它的动作
annotate-instructions = 说明（模型收到的题目原文）
annotate-untranslated = 题目按模型收到的原样以英文显示，不做翻译：它是基准的一部分。
annotate-untranslated-actions = 动作描述是基准的一部分，按数据集中的原文显示，不做翻译。
annotate-finished = 您已完成此条目。
annotate-attention-keep-forward = 注意力检查：无论动作描述如何，请按候选图像列出的顺序放入槽位：Next State 1 放入槽位 1，Next State 2 放入槽位 2，依此类推。
annotate-attention-reverse-forward = 注意力检查：无论动作描述如何，请把图像按相反顺序放入槽位：最后列出的候选图像放入槽位 1，倒数第二张放入槽位 2，依此类推，Next State 1 放入最后一个槽位。
annotate-attention-keep-inverse = 注意力检查：无论图像显示什么，请按候选动作列出的顺序放入槽位：Action 1 放入槽位 1，Action 2 放入槽位 2，依此类推。
annotate-attention-reverse-inverse = 注意力检查：无论图像显示什么，请把动作按相反顺序放入槽位：最后列出的候选动作放入槽位 1，倒数第二个放入槽位 2，依此类推，Action 1 放入最后一个槽位。
annotate-next = 继续下一个
annotate-answer = 答案
annotate-steps = 步骤：第 k 个动作得到第 k 张图像
annotate-transitions = 状态转变（按顺序）
annotate-enlarge = 放大 { $name }
annotate-alt-current = 当前状态，动作由此开始（{ $name }）
annotate-current-caption = { $name }：动作由此开始
annotate-alt-before = 第 { $index } 个转变，之前的状态（{ $name }）
annotate-alt-after = 第 { $index } 个转变，之后的状态（{ $name }）
annotate-alt-candidate = 候选 { $name }
annotate-undo = 撤销
annotate-submit = 提交答案
annotate-candidate-images = 候选图像
annotate-candidate-actions = 候选动作
annotate-shuffled = （已打乱）
annotate-keyboard-help = 将卡片拖到槽位上，或先点击卡片再点击槽位。键盘操作：方向键在槽位和卡片之间移动（检视区随之更新）；在卡片上按槽位编号即可放入；在槽位或已放置的卡片上按 Backspace 清除；把卡片放到已占用的槽位会交换位置；Ctrl+Z 或“撤销”按钮可撤销。
annotate-inspector = 检视区：放大显示当前焦点所在的图像
annotate-inspector-hint = 将指针移到图像上或让图像获得焦点，即可在此放大查看。
annotate-skip-summary = 跳过此条目或报告问题
annotate-reason = 原因
annotate-skip = 跳过
annotate-flag = 报告问题
annotate-lightbox = 放大的图像
annotate-close = 关闭

## 标注页面脚本的提示（实时播报区、状态、标签）
js-slot-empty = 槽位 { $slot }：空
js-slot-filled = 槽位 { $slot }：{ $name }
js-card-in-slot = 在槽位 { $slot }
js-saving = 正在保存…
js-saved = 已保存
js-not-saved = 未保存：{ $error }
js-placed = { $name } 已放入槽位 { $slot }。
js-swapped-moved = { $name } 已移到槽位 { $slot }。
js-swapped-returned = { $name } 已放回候选区。
js-cleared = 槽位 { $slot } 已清空；{ $name } 已放回候选区。
js-nothing-to-undo = 没有可撤销的操作。
js-undone = 已撤销。
js-card-selected = 已选中 { $name }：请选择槽位。
js-no-such-slot = 没有槽位 { $key }；槽位编号为 1 到 { $count }。
js-slot-selected = 已选中 { $name }：请选择另一个槽位以移动它。
js-submitted = 答案已提交。
js-not-submitted = 未提交：{ $error }
js-before-start = 之前：{ $name }
js-before-empty = 之前：槽位 { $slot } 为空
js-before-slot = 之前：槽位 { $slot }，{ $name }
js-focus-slot-empty = 槽位 { $slot }：空
js-focus-slot = 槽位 { $slot }：{ $name }
js-transition-before = 第 { $index } 个转变，之前：{ $name }
js-transition-after = 第 { $index } 个转变，之后：{ $name }
js-not-placed = { $name }（未放置）

## 首页：数据集
home-submitting = 要提交模型结果？请参阅
home-api-docs = API 文档。
home-empty = 此数据库中还没有数据集。
home-import = 导入一个 ENACT 发布版本（包含 QA/enact_ordering.jsonl 及其图像的文件夹）：
home-demo = 或者使用内置的演示数据集启动服务：
home-items-from-tasks = { $items } 个条目，来自 { $tasks } 个任务
home-imported = 导入于 { $date }
home-leaderboard = 排行榜
home-counts-caption = 按方向和步长统计的条目数（L = 图像数量）
col-all = 全部
col-step-length = 步长
col-task = 任务

## 数据集的条目
dataset-download = 以 ENACT 发布归档（tar）下载全部条目
dataset-download-what = — 包括 QA/enact_ordering.jsonl 和图像。仅当该数据集的答案公开时才包含答案。
dataset-any = 任意
dataset-show = 显示
dataset-no-match = 没有符合这些筛选条件的条目。
dataset-shown = 第 { $first }–{ $last } 项，共 { $total } 项
pager-label = 分页
pager-previous = 上一页
pager-next = 下一页

## 单个条目（只读）
item-crumb = 条目
item-counts = { $images } 张图像，{ $actions } 个动作
item-type = 类型
item-images = 图像
item-images-forward = （先是当前状态，然后是条目中打乱顺序的未来状态）
item-images-inverse = （按时间顺序）
item-alt-image = 条目中位置 { $position } 的图像（{ $name }）
item-actions = 动作
item-actions-forward = （按顺序）
item-question = 完整题目文本（与模型收到的相同）

## 排行榜
leaderboard-title = 排行榜：{ $dataset }
leaderboard-heading = 排行榜：
leaderboard-policy = 严格计分：数据集中的每个条目都计入；缺失或无法读取的答案记 0 分。
leaderboard-metrics = TA = 任务准确率，PA = 成对准确率，单位为百分比。区间为对条目做 95% 百分位自助法（1,000 次重采样）得到的置信区间。
leaderboard-metric-version = 指标版本 { $version }；用旧版本计算的行会被标记为
leaderboard-older-metric = 旧版指标
leaderboard-error-analysis = 错误分析
leaderboard-compare = 比较两行
leaderboard-explore = 浏览每个作答
leaderboard-empty = 该数据集还没有已发布的提交。
leaderboard-how-to-submit = 使用 API 令牌提交 ENACT 模型输出 JSONL：
leaderboard-ranked-by = 排序依据：
leaderboard-ranking-help = （点击某列的 TA 或 PA 可按该列排序）；显示值相同者名次相同。
leaderboard-every-listed = 列出了所有已发布的提交。
leaderboard-one-per-model = 每个模型一行
leaderboard-latest-listed = 每个账号和模型一行：显示其最新发布的提交。
leaderboard-every-submission = 全部提交
leaderboard-all-models = 全部模型
leaderboard-only-model = 仅模型 { $model }
leaderboard-only-account = 仅账号 { $account }
leaderboard-only-model-of-account = 仅账号 { $account } 的模型 { $model }
leaderboard-caption = 总体、正向和逆向世界建模；按步长 L（图像数量）细分
leaderboard-draw = 在图表中绘制
leaderboard-draw-model = 在图表中绘制 { $model }
leaderboard-model = 模型
leaderboard-overall = 总体
leaderboard-forward = 正向世界建模
leaderboard-inverse = 逆向世界建模
leaderboard-coverage = 覆盖率
leaderboard-parse-failures = 解析失败
leaderboard-submitted = 提交日期
leaderboard-ta-ci = TA 95% 置信区间
leaderboard-pa-ci = PA 95% 置信区间
leaderboard-baseline = 基线
leaderboard-attempts = { $count } 次尝试
leaderboard-few-answers = 仅 { $count } 个答案：少于 { $minimum } 个
leaderboard-outdated = 使用指标版本 { $version } 计算（当前版本：{ $current }）；在管理员重新计分之前，不能与其他行比较
leaderboard-human-items = { $items } / { $total } 个条目
leaderboard-human-annotators = { $count } 名标注者
leaderboard-human-answers = { $count } 个答案
leaderboard-human-gold = ；{ $count } 个金标条目上的答案不计入
leaderboard-human-excluded = ；{ $count } 名标注者被管理员排除
leaderboard-human-unranked = ；不参与排名
intervals-note = 区间：95 % 百分位自助法，重抽样单位为{ $resampling }。同一活动（ENACT 的 task_name）的题目共享场景、往往一同出错，因此默认按整个活动重抽样。
leaderboard-resample-items = 改为逐个题目重抽样
leaderboard-resample-activities = 按整个活动重抽样（默认）
leaderboard-intervals-by-items = 此行的区间按题目重抽样：它在本平台改为按活动重抽样之前计分
leaderboard-human-note = “人类”行仅作参照，从不与模型一起排名；标有 † 的数值所依据的人类答案少于五个。金标条目（混入标注者队列、答案已知、用于检查其工作的条目）上的答案从不计入此行，被管理员排除的标注者的答案也不计入。
leaderboard-reported-count = 此数据集有 { $count } 条论文发表的结果（报告行）。
leaderboard-reported-show = 显示报告行
leaderboard-reported-hide = 隐藏报告行
leaderboard-reported-badge = 报告
leaderboard-reported-source = 来源：{ $source }
leaderboard-reported-unranked = 不参与排名：报告行
leaderboard-reported-note = 报告行是论文发表的数值，以数据形式录入：未经本平台计分，没有区间，也没有逐条目数据，从不与本平台的行一起排名（其名次留空）。论文附录表格只给出各步长的数值，因此其总体、正向和逆向合计为空。
leaderboard-provenance-run = 运行
leaderboard-provenance-run-meaning = 本平台亲自询问模型并为其保存的回复计分；链接显示运行的印记
leaderboard-provenance-submitted = 提交
leaderboard-provenance-submitted-meaning = 提交者上传的答案；本平台为其计分，但未见模型作答
leaderboard-provenance-filter = 只显示这类行：
leaderboard-provenance-all = 任意来源
leaderboard-model-link = 模型介绍
leaderboard-challenge-public = 挑战进行中：这些数值只基于公开部分，即 { $total } 个条目中的 { $public } 个。非公开部分（{ $total } 个中的 { $private } 个）将于 { $deadline }（UTC）揭晓，最终排名以其为准。
leaderboard-challenge-public-no-deadline = 挑战进行中：这些数值只基于公开部分，即 { $total } 个条目中的 { $public } 个。非公开部分（{ $total } 个中的 { $private } 个）将由管理员揭晓，最终排名以其为准。
leaderboard-challenge-public-after = 公开部分的数值（{ $total } 个条目中的 { $public } 个），即挑战期间的排行榜。非公开部分已于 { $revealed } 揭晓。
leaderboard-challenge-private = 最终排名：非公开部分已于 { $revealed } 揭晓。这些数值基于其 { $private } 个条目（共 { $total } 个），针对每个账户选定的提交（未选定时为其最新提交）；每行显示其在公开部分的名次及变化。
leaderboard-challenge-preview = 管理员预览：基于非公开部分（{ $total } 个条目中的 { $private } 个）的最终排名，即现在揭晓时的结果。揭晓之前提交者看不到它。
leaderboard-challenge-show-preview = 预览最终排名
leaderboard-challenge-show-final = 最终排名
leaderboard-challenge-show-public = 公开部分的排行榜
leaderboard-account-submissions = 该账户共提交 { $count } 次
leaderboard-standing = 公开部分第 { $public } 名，非公开部分第 { $private } 名：{ $change }
leaderboard-rank-up = 上升 { $places } 名
leaderboard-rank-down = 下降 { $places } 名
leaderboard-rank-same = 名次不变
leaderboard-page-of = 第 { $page } 页，共 { $pages } 页
leaderboard-ranked-rows = { $count } 个排名行
leaderboard-chart-heading = 任务准确率随步长的变化
leaderboard-chart-checked = 表中勾选的模型，以及“人类”行和基线。
leaderboard-chart-best = 按 { $sort } 排名前十的模型，以及“人类”行和基线。
leaderboard-chart-draw = 绘制勾选的模型
leaderboard-chart-label = 任务准确率（%）随步长 L 的变化，每个模型一条线；分为正向和逆向两个面板
leaderboard-axis-step = 步长 L
leaderboard-axis-ta = TA（%）
leaderboard-group-overall = 总体
leaderboard-group-forward = 正向
leaderboard-group-inverse = 逆向
leaderboard-sort = { $group } { $metric }
leaderboard-sort-step = { $group } { $metric }（L={ $step }）

## 错误分析
errors-heading = 错误分析：{ $dataset }
errors-leaderboard = 排行榜
errors-explanation = 每个长度正确的答案都会与真实答案逐步比较：匹配真实的和预测的状态变化，其余按 ENACT 论文的分类（极性反转、谓词替换、实体替换、遗漏、幻觉）以及所涉及的内容归类。手部数据统计每个夹爪的抓取变化；“混淆”指某只手的真实变化被归给另一只手的比例。
errors-empty = 还没有已发布的提交，也没有人类答案。
errors-examples-withheld = 不显示示例：数据集“{ $dataset }”的答案是隐藏的，因此只显示汇总数据。
errors-row = 行
errors-overall = 总体
errors-structural = 结构性错误
errors-semantic = 语义错误
errors-hands = 手部
errors-structural-caption = 各行错误按结构类别的占比
errors-semantic-caption = 各行错误按语义类别的占比
errors-hands-caption = 左手和右手的精确率、召回率和混淆率；误差线为一个标准误
errors-of = { $row } 的错误
errors-all-rows = { $dataset } 的所有行
errors-row-structural-caption = 错误按结构类别的占比，正向和逆向
errors-row-semantic-caption = 错误按语义类别的占比，正向和逆向
errors-row-hands-caption = 左手和右手的精确率、召回率和混淆率，正向和逆向；误差线为一个标准误
errors-examples = 示例
errors-none = 没有可显示的错误。
errors-class = 类别
errors-step = 步骤
errors-true-change = 真实变化
errors-predicted-change = 预测变化
errors-analysed = 已分析
errors-not-analysed = 未分析
errors-errors = 错误数
errors-structural-share = 结构性（占错误的比例）
errors-semantic-share = 语义（占错误的比例）
errors-hands-se = 手部（± 标准误）
errors-accepted-incomplete = 被接受但不完整
errors-answers = 答案
errors-steps = 步骤
errors-polarity-inversion = 极性反转
errors-predicate-substitution = 谓词替换
errors-entity-substitution = 实体替换
errors-omission = 遗漏
errors-hallucination = 幻觉
errors-spatial-relations = 空间关系
errors-functional-states = 功能状态
errors-material-states = 材料状态
errors-agent-interaction = 智能体交互
errors-hand-left = 左手
errors-hand-right = 右手
errors-precision = 精确率
errors-recall = 召回率
errors-mixing = 混淆率

## 消融研究
studies-title = 消融研究
studies-explanation = 一项研究会用其他图像（图像真实感、相机、机器人外观）重新提出基线数据集的问题，并针对某个模型或“人类”行，报告成对准确率在每个变体上的变化：Δ 及论文中的 Welch 检验，以及在相同条目上的配对检验。
studies-empty = 还没有研究。管理员可以用 enact-hub study create 创建，或在此页面创建：
studies-study = 研究
studies-baseline = 基线
studies-variants = 变体
studies-created = 创建
studies-created-by = 由 { $who } 创建于 { $date }
study-title = 研究：{ $name }
study-items = { $count } 个条目
study-all = 全部研究
study-variants-caption = 各变体及其条目与基线条目的对齐情况
study-family = 类别
study-variant = 变体
study-aligned = 已对齐
study-by-id = 按 id
study-by-key-frames = 按任务、类型和关键帧
study-unaligned = 未对齐（基线 / 变体）
study-judged-differently = 判定规则不同
study-not-computed = 未计算
study-judged-warning = 有 { $count } 个已对齐条目的判定规则与基线不同（真实答案或签名表不同），因此其得分差异并非仅由图像造成。请使用基线的场景图导入变体：
study-compare = 比较
study-choose = 选择模型…
study-human = 人类（标注者）
study-per-step = 按步长
study-show = 显示报告
study-report-heading = { $row } 在各变体上相对基线的表现
study-delta-explained = Δ = 在已对齐条目上，变体的平均成对准确率 − 基线的平均成对准确率。颜色：双尾 Welch 检验 p 值（论文使用的检验）所在区间；红色越深越显著。下载：
study-all-files = 全部文件（tar）
study-cells-caption = 按变体和方向的 Welch 检验（非配对，同论文）和配对检验
study-n = n（基线 / 变体）
study-signs = 符号（↑ ↓ =）
study-handedness = 左右手（论文的 C.2 面板）
study-handedness-explained = 基线和各变体上左手和右手的精确率、召回率和混淆率（某只手的真实变化被归给另一只手的比例），± 标准误。

## 接受邀请
invite-title = 设置密码
invite-welcome = 欢迎，{ $name }
invite-choose = 请设置密码（至少 { $count } 个字符）。此链接只能使用一次。
invite-repeat = 再次输入
invite-submit = 设置密码并开始
errors-figures-table = 各行的错误数据
errors-examples-of = 示例：{ $category }

## 论文表格 (/datasets/{dataset}/paper)
paper-title = 论文表格
paper-heading = 论文表格：{ $dataset }
paper-explanation = 基于本数据集生成的 ENACT 结果表格：论文发表的结果（由管理员录入）与本平台自己的行（每个模型最新公开的提交，以及本平台标注员的人类行）并列。最佳与次佳按论文的方式在各类别内标出；除非元数据指定类别，本平台的行自成一类。
paper-leaderboard = 排行榜
paper-models = 行
paper-models-hint = 模型名称，以逗号分隔，按打印顺序排列；留空则包含所有行。
paper-metric = 指标
paper-metric-both = 两张表
paper-task-accuracy = 任务准确率
paper-pairwise-accuracy = 成对准确率
paper-intervals = 显示本平台各行的 95% 自助法置信区间
paper-apply = 生成表格
paper-download = 下载全部表格、图和 provenance.json（tar）
paper-marks = 标记：
paper-mark-first = 类别内最佳
paper-mark-second = 类别内次佳
paper-standalone = 独立 .tex
paper-model = 模型
paper-source = 来源
paper-forward = 正向世界建模
paper-inverse = 逆向世界建模
paper-category-proprietary = 闭源模型
paper-category-open-weight = 开放权重模型
paper-category-human = 人类表现
paper-figure-alt = 按步长的{ $metric }，正向与逆向，每行一条线
paper-figure-caption = 按步长的{ $metric }。
paper-error-analysis = 错误分析
paper-error-analysis-alt = 每个本站行的结构性错误类别（极性反转、谓词替换、实体替换、遗漏、幻觉）占比，正向与逆向
paper-error-analysis-caption = 所选本站行的错误分布，按方向；已发表的行没有逐题答案可供分析。
paper-error-analysis-none = 未选择任何本站行（提交或人类行），因此没有错误分析图：已发表的行没有逐题答案可供分析。
paper-studies = 本数据集的研究
paper-study-alt = 研究 { $study } 对 { $row } 的热图：各变体相对本数据集的平均成对准确率差 Δ，正向与逆向，颜色表示 p 值区间
paper-study-caption = 研究 { $study }，按 { $row } 报告。
paper-study-link = 该研究
paper-reproduction = 复现检查
paper-reproduction-none = 在本数据集上，尚无论文发表的模型也在本平台上计分。
paper-reproduction-explanation = 论文发表且本平台也计分的每个模型（同名），逐格列出：发表值、本平台的值、差值（百分点）、本平台的 95% 自助法区间，以及发表值是否落在区间内。
paper-cell = 单元格
paper-reported = 发表值
paper-hub = 本平台
paper-difference = 差值
paper-interval = 本平台区间
paper-inside = 发表值在区间内？
paper-inside-yes = 在区间内
paper-inside-no = 在区间外

## 逐题比较排行榜的两行（/datasets/{dataset}/compare）
compare-title = 比较两行
compare-heading = 比较两行：{ $dataset }
compare-explanation = 在两行都作答过的题目上比较排行榜的两行。排行榜区间相互重叠并不能说明谁更好；配对比较问的是：一方答对而另一方答错的题目各有多少。每个差值（A − B，以百分点计）附有配对自助法区间，任务成功与否另做 McNemar 精确检验。
compare-leaderboard = 排行榜
compare-row-a = 行 A
compare-row-b = 行 B
compare-rows-hint = 模型名称（即其排行榜行）或提交编号。
intervals-resample = 区间重抽样单位
intervals-resampling-activities = 整个活动及其全部题目
intervals-resampling-items = 逐个题目
compare-apply = 比较
compare-no-rows = 此排行榜尚无公开的提交。
compare-result = { $a } 对比 { $b }
compare-method = 区间：{ $level } % 配对百分位自助法，重抽样单位为{ $resampling }。
compare-resamples = 共 { $count } 次重抽样。
compare-metric-versions = 两行按不同的指标版本计分（{ $a } 与 { $b }）：对较旧的一行重新计分后方可比较。
compare-unpaired = 有 { $count } 道题只在其中一行有判定，未计入。
compare-table = 两行的任务准确率与成对准确率、二者之差及 McNemar 检验
compare-cell = 题目
compare-n = 数量
compare-ta-a = A 的 TA
compare-ta-b = B 的 TA
compare-ta-difference = TA A − B [区间]
compare-a-only = 仅 A 答对
compare-b-only = 仅 B 答对
compare-mcnemar = McNemar p
compare-pa-a = A 的 PA
compare-pa-b = B 的 PA
compare-pa-difference = PA A − B [区间]
compare-significant = 小于 0.05
compare-reading = 区间不含 0 且 McNemar p 小于 0.05（粗体）时，差异不太可能出于偶然。题目来自少数活动时，按活动重抽样给出的区间更宽，也更诚实。
compare-overall = 全部题目
compare-forward = 正向
compare-inverse = 逆向
compare-only-a = 仅 { $row } 答对的题目
compare-only-b = 仅 { $row } 答对的题目
compare-none = 无。
compare-items-hidden = 此数据集的答案不公开：逐题判定仅对管理员显示。

## 每道题对照每一行（/datasets/{dataset}/explore）
explore-title = 浏览作答
explore-heading = 每道题、每一行：{ $dataset }
explore-explanation = 数据集的每道题对照排行榜的每一行及人类列，列出每个答案的判定。人类列取人类行所计入的标注员答案的多数：超过一半答对即为答对。模型行缺少答案按答错计。可按题目类型和模式筛选，按难度（答错的行所占比例）或按某一行排序；每个选项都注明会显示多少道题。
explore-leaderboard = 排行榜
explore-activity = 活动
explore-pattern = 模式
explore-pattern-any = 全部题目
explore-pattern-humans-right = 人类答对、所有模型答错
explore-pattern-disagree = 模型之间意见不一
explore-pattern-unparseable = 有模型的答案无法解析
explore-pattern-only = 仅 { $row } 答对
explore-sort = 排序
explore-sort-difficulty = 最难的在前
explore-sort-wrong = { $row }：答错的在前
explore-sort-right = { $row }：答对的在前
explore-option-count = { $label }（{ $count }）
explore-apply = 显示
explore-matching = { $total } 道题中有 { $matching } 道符合。
explore-permalink = 本视图的链接
explore-csv = 所有符合条件题目的 CSV
explore-legend = 判定：
explore-none = 没有题目符合此视图。
explore-table = 符合条件题目的判定，第 { $page } 页，共 { $pages } 页
explore-kind = 类型
explore-wrong-rows = 答错的行
explore-human = 人类
explore-baseline = 基线
explore-right-count = 答对 { $count } 道
explore-page = 第 { $page } 页，共 { $pages } 页

## 题目页上的作答
item-answers = 作答
item-truth = 正确顺序：
item-gold = 金标准题
item-answers-models = 排行榜行
item-answers-humans = 标注员
item-answers-no-models = 尚无公开的提交回答此题。
item-answers-no-humans = 尚无标注员回答此题。
item-answers-hidden = 此数据集的答案不公开：各题的作答仅对管理员显示。
item-answer-who = 作答者
item-answer-order = 答案
item-answer-verdict = 判定
item-answer-pairwise = 成对准确率
item-answer-why = 原因
item-answer-baseline = 基线
item-answer-excluded = 已从人类行中排除
item-verdict-exact = 完全正确
item-verdict-equivalent = 判为等价
item-verdict-wrong = 错误
item-verdict-unparseable = 无法解析
item-verdict-missing = 缺失
item-why = 验证器拒绝的步骤
item-why-step = 第 { $step } 步（标签 { $label }）
item-why-implied = 答案蕴含而正确答案没有的变化：
item-why-missed = 正确步骤有而答案没有的变化：
item-why-pairs = 顺序颠倒的标签对：
